"""The contract between the parts: one definition of each shared fact.

The C header is what the contract generates, the parts import the contract rather than
retype it, and `check` refuses what a later stage would refuse for its size.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

from gliderplan import contract
from gliderplan.contract.c_header import c_header

ROOT = Path(__file__).resolve().parents[1]
HEADER = ROOT / "runtime" / "include" / "gp_contract.h"
PACKAGES = ("cli", "language", "planner", "power_models", "runtime", "sim")
CONTRACT_NAMES = frozenset(name for name in vars(contract) if not name.startswith("_")
                           and name[0].isupper())


def test_the_committed_header_is_the_one_the_contract_generates():
    assert HEADER.read_text() == c_header(), (
        "runtime/include/gp_contract.h is stale: run "
        "`python -m gliderplan.contract > runtime/include/gp_contract.h`")


def test_the_header_carries_every_value_of_the_contract():
    text = HEADER.read_text()
    defined = {m[1]: int(m[2], 0) for m in re.finditer(r"#define GP_(\w+) (0x[0-9A-F]+|\d+)u?\b",
                                                        text)}
    for name in ("MAX_STATES", "MAX_STACK_DEPTH", "MAX_EVENTS_PER_STATE", "MAX_NAME_LENGTH",
                 "N_SENSORS", "FLIGHT_SENSORS_MASK", "NO_STATE", "MAX_PAYLOAD"):
        assert defined[name] == getattr(contract, name), name
    for sensor in contract.SENSORS:
        assert f"GP_SENSOR_{sensor.name.upper()} = {sensor.index}," in text
    assert f"GP_TR_CALL = {contract.TransitionKind.CALL}," in text
    assert f"GP_EXIT_LINK_LOST = {contract.RuntimeExit.LINK_LOST}," in text


def _python_sources() -> list[Path]:
    return [p for package in PACKAGES for p in sorted((ROOT / package).rglob("*.py"))]


@pytest.mark.parametrize("path", _python_sources(), ids=lambda p: str(p.relative_to(ROOT)))
def test_no_module_redefines_a_fact_of_the_contract(path):
    tree = ast.parse(path.read_text())
    for node in tree.body:
        targets = [node.target] if isinstance(node, ast.AnnAssign) else \
            node.targets if isinstance(node, ast.Assign) else []
        names = {n.id for t in targets for n in ast.walk(t) if isinstance(n, ast.Name)}
        if isinstance(node, ast.ClassDef):
            names = {node.name}
        assert not names & CONTRACT_NAMES, (
            f"{path.name}:{node.lineno} defines {sorted(names & CONTRACT_NAMES)}; "
            "import it from gliderplan.contract")


def _c_sources() -> list[Path]:
    runtime = ROOT / "runtime"
    return [p for p in sorted([*runtime.glob("include/*.h"), *runtime.glob("src/*.c")])
            if p != HEADER]


@pytest.mark.parametrize("path", _c_sources(), ids=lambda p: p.name)
def test_no_c_file_redefines_a_fact_of_the_header(path):
    generated = set(re.findall(r"^#define (GP_\w+)|^\s+(GP_\w+) = ", HEADER.read_text(), re.M))
    names = {a or b for a, b in generated}
    text = path.read_text()
    defined = set(re.findall(r"^#define (GP_\w+)", text, re.M))
    defined |= set(re.findall(r"^\s+(GP_\w+) = ", text, re.M))
    assert not defined & names, f"{path.name} defines {sorted(defined & names)} again"
    # the sensor array is indexed by name (GP_SENSOR_*), never by a bare number
    assert not re.search(r"sensors\[\d+\]", text), f"{path.name} indexes sensors by number"

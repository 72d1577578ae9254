"""The C runtime's view of the contract: `runtime/include/gp_contract.h`, generated.

Each fact keeps its Python name with a `GP_` prefix (`MAX_STACK_DEPTH` becomes
`GP_MAX_STACK_DEPTH`), enumerations get their members' names behind a prefix of their
own, and every value carries the comment it has in the contract. Regenerate with

    python -m gliderplan.contract > runtime/include/gp_contract.h

tests/test_contract.py fails when the committed header differs from this output.
"""

from __future__ import annotations

import inspect
import re
import struct
from enum import IntEnum

from gliderplan import contract

# The facts the runtime uses, by their names in the contract.
CONSTANTS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("limits of the mission tables and the plan file", (
        "MAX_STATES", "MAX_VARIABLES", "MAX_STACK_DEPTH", "MAX_EVENTS_PER_STATE",
        "MAX_PROFILE_ALTERNATIVES", "MAX_PROFILE_ARGS", "MAX_ROUTE_POINTS",
        "MAX_SWEEP_WAYPOINTS", "MAX_NAME_LENGTH", "MAX_PLAN_SENSORS", "MAX_PLAN_BYTES",
        "MAX_PLAN_LINE_BYTES", "MAX_PLAN_COMPONENTS", "MAX_PLAN_ASSUMPTIONS",
        "PLAN_FORMAT_VERSION")),
    ("what a plan may ask for", (
        "MAX_PLAN_TIME_S", "MAX_PLAN_SPEED_MPS", "MAX_PLAN_THRUST_W", "MAX_PLAN_ENERGY_J",
        "MAX_PLAN_INFLECTIONS",
        "MAX_BOARD_CLOCKS", "CLOCK_TOLERANCE_MHZ", "NO_BOARD", "PLAN_ROUNDING")),
    ("signed plans", ("PLAN_KEY_BYTES", "MAX_PLAN_SEQUENCE")),
    ("plan updates (docs/plan-update.md)", (
        "UPDATE_FORMAT_VERSION", "MAX_UPDATE_BYTES", "UPDATE_HASH_BYTES",
        "UPDATE_HEADER_BYTES", "UPDATE_MAX_DIGITS", "UPDATE_MAX_EXPONENT")),
    ("the library routines (docs/pilot.md)", (
        "SURFACE_PITCH_RAD", "TRACK_WINDOW", "YO_ALTITUDE_ARG", "THERMOTRACKYO_ALTITUDE_ARG",
        "WAYPOINT_RADIUS_M", "EARTH_RADIUS_M")),
    ("the serial link (docs/protocol.md)", (
        "PROTOCOL_VERSION", "MAX_PAYLOAD", "MAX_WIRE", "PLAN_PIECE", "COMMAND_MAX_SIZE",
        "MISSION_HASH_BYTES", "HELLO_FIXED_BYTES", "NO_STATE", "BAUD", "RETRANSMIT_MS",
        "LINK_TIMEOUT_S")),
)
LINE_LENGTH = 100
HEX = frozenset({"NO_STATE"})  # byte values written in hex, as docs/protocol.md has them
# Bits of a message's flags byte, as C enumerations.
FLAGS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("COMMAND's flags", ("FLAG_SURFACE", "FLAG_DONE", "FLAG_CLIMBING", "FLAG_HEADING",
                         "FLAG_ENVELOPE", "FLAG_HEADING_HOLD")),
    ("SENSORS's flags", ("SENSORS_MASK", "SENSORS_RESYNC")),
)
# Enumeration -> (C type name, prefix of its members).
ENUMS: tuple[tuple[type[IntEnum], str, str], ...] = (
    (contract.MessageType, "gp_msg_type", "GP_MSG_"),
    (contract.TransitionKind, "gp_transition_kind", "GP_TR_"),
    (contract.CommandField, "gp_command_field", "GP_CMD_"),
    (contract.ReleaseReason, "gp_release_reason", "GP_RELEASE_"),
    (contract.RuntimeExit, "gp_exit_status", "GP_EXIT_"),
    (contract.UpdateField, "gp_update_field", "GP_UF_"),
    (contract.UpdateStatus, "gp_update_status", "GP_UPDATE_"),
    (contract.EnvelopeAction, "gp_envelope_action", "GP_ENVELOPE_"),
    (contract.EnvelopeLimit, "gp_envelope_limit", "GP_LIMIT_"),
)


def sensor_index(name: str) -> str:
    """The C name of a sensor's index in the sensor array, e.g. GP_SENSOR_DEPTH."""
    return f"GP_SENSOR_{name.upper()}"


def _comments(definitions: object) -> dict[str, str]:
    """NAME -> what the source of a module's (or a class's) top level says of NAME: the
    comment on its line, else the comment lines right above it."""
    found: dict[str, str] = {}
    above: list[str] = []
    for line in inspect.getsource(definitions).splitlines():
        text = line.strip()
        if text.startswith("#"):
            above.append(text.lstrip("# "))
            continue
        indent = len(line) - len(line.lstrip())
        match = re.fullmatch(r"(\w+) = [^#]*?(?:#\s*(.+))?", text)
        if match and indent == (4 if isinstance(definitions, type) else 0):
            note = match[2] or " ".join(above)
            if note:
                found[match[1]] = note
        above = []
    return found


def _value(name: str, value: float | str) -> str:
    """C text of a value: `repr` of a float is the shortest that reads back exactly; a
    word becomes a string literal."""
    if isinstance(value, str):
        return f'"{value}"'
    return f"0x{value:02X}u" if name in HEX else repr(value)


def _noted(code: str, note: str | None) -> str:
    """A line of C with its doc comment after it, or above it if the line gets too long."""
    if not note:
        return code
    after = f"{code}  /**< {note} */"
    if len(after) <= LINE_LENGTH:
        return after
    indent = code[:len(code) - len(code.lstrip())]
    return f"{indent}/** {note} */\n{code}"


def c_header() -> str:
    """The text of gp_contract.h."""
    notes = _comments(contract)

    def define(name: str, value: str) -> str:
        return _noted(f"#define GP_{name} {value}", notes.get(name))

    lines = ["/**", " * @file gp_contract.h",
             " * @brief The facts the runtime shares with the rest of gliderplan, generated",
             " *        from gliderplan.contract: do not edit; run",
             " *        `python -m gliderplan.contract > runtime/include/gp_contract.h`.",
             " */", "#ifndef GP_CONTRACT_H", "#define GP_CONTRACT_H", ""]
    for title, names in CONSTANTS:
        lines += [f"/* ---- {title} */", ""]
        lines += [define(name, _value(name, getattr(contract, name))) for name in names]
        lines.append("")
    lines += ["/* ---- the sensor array: GP_SENSOR_<NAME> is the index of sensor NAME */", "",
              define("N_SENSORS", str(contract.N_SENSORS)),
              define("FLIGHT_SENSORS_MASK", f"0x{contract.FLIGHT_SENSORS_MASK:X}u"), "",
              "enum {",
              *(_noted(f"    {sensor_index(s.name)} = {s.index},",
                       f"{s.description} [{s.unit}]") for s in contract.SENSORS),
              "};", ""]
    for title, names in FLAGS:
        lines += [f"/* ---- {title} */", "", "enum {"]
        lines += [_noted(f"    GP_{name} = {getattr(contract, name)}u,", notes[name])
                  for name in names]
        lines += ["};", ""]
    sizes = ", ".join(str(struct.calcsize(f)) for f in contract.COMMAND_FIELD_FORMATS)
    lines += ["/** Bytes of each COMMAND field on the wire, in gp_command_field order. */",
              f"#define GP_COMMAND_FIELD_BYTES {{{sizes}}}",
              f"#define GP_N_COMMAND_FIELDS {len(contract.CommandField)}", ""]
    for enum, type_name, prefix in ENUMS:
        notes = _comments(enum)
        lines += [f"/** {(enum.__doc__ or '').strip().splitlines()[0]} */", "typedef enum {"]
        packed = ""  # members without a note share lines
        for member in enum:
            value = f"0x{member.value:02X}" if enum is contract.MessageType else member.value
            code = f"{prefix}{member.name} = {value},"
            if packed and (member.name in notes
                           or len(f"    {packed} {code}") > LINE_LENGTH):
                lines.append(f"    {packed}")
                packed = ""
            if member.name in notes:
                lines.append(_noted(f"    {code}", notes[member.name]))
            else:
                packed = f"{packed} {code}".lstrip()
        lines += [f"    {packed}"] if packed else []
        lines += [f"}} {type_name};", ""]
    lines.append("#endif /* GP_CONTRACT_H */")
    return "\n".join(lines) + "\n"

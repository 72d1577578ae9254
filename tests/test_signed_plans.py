"""Signed plans end to end: `gliderplan keygen`, `plan --sign`, and `sim --key` on both
runtimes (the C runtime gets the plan uploaded over the link and checks it itself); a
tampered plan fails the run with exit 1 and one line; the key file's rules."""

from __future__ import annotations

import json
import re
import shutil
import stat
import zlib
from pathlib import Path

import pytest

from gliderplan.cli.main import main
from gliderplan.planner.planfile import PlanFileError, read_plan_bytes
from gliderplan.planner.signing import (
    KeyFileError,
    check_signature,
    read_key,
    sign_plan,
    unsigned_part,
)

ROOT = Path(__file__).resolve().parents[1]
FIG2 = ROOT / "examples" / "fig2_annotated.mission"


@pytest.fixture(scope="module")
def signed(tmp_path_factory) -> tuple[Path, Path]:
    """A key and the annotated Fig. 2's plan signed with it as plan 5."""
    work = tmp_path_factory.mktemp("signed")
    assert main(["keygen", "-o", str(work / "vehicle.key")]) == 0
    assert main(["plan", str(FIG2), "-o", str(work / "fig2.plan"), "--sign",
                 str(work / "vehicle.key"), "--seq", "5"]) == 0
    return work / "vehicle.key", work / "fig2.plan"


def recrc(data: bytes) -> bytes:
    """A forger's edit: the plan's CRC-32 made right again, its signature left as it was."""
    text = data.decode()
    body = text[:text.index("crc32 ")]
    tail = text[text.index("\nseq ") + 1:]
    return (body + f"crc32 {zlib.crc32(body.encode()):08x}\n" + tail).encode()


def test_keygen_writes_a_private_key_once(tmp_path, capsys):
    key = tmp_path / "k.key"
    assert main(["keygen", "-o", str(key)]) == 0
    assert stat.S_IMODE(key.stat().st_mode) == 0o600
    assert re.fullmatch(r"[0-9a-f]{64}\n", key.read_text())
    first = key.read_text()
    assert main(["keygen", "-o", str(key)]) == 2  # never over a key a vehicle may hold
    assert key.read_text() == first
    assert "exists" in capsys.readouterr().err
    assert main(["keygen", "-o", str(tmp_path / "other.key")]) == 0
    assert (tmp_path / "other.key").read_text() != first


def test_write_new_key_is_the_keygen_command_as_one_call(tmp_path):
    from gliderplan.contract import ExitCode
    from gliderplan.planner.signing import write_new_key

    key = tmp_path / "k.key"
    write_new_key(key)
    assert stat.S_IMODE(key.stat().st_mode) == 0o600 and len(read_key(key)) == 32
    first = key.read_text()
    with pytest.raises(KeyFileError, match="exists") as refused:
        write_new_key(key)  # the error the command prints, with its exit code
    assert refused.value.exit_code == ExitCode.USAGE and key.read_text() == first


def test_plan_sign_reports_the_upload_size_and_signs_what_the_reader_reads(signed, capsys):
    key, plan = signed
    data = plan.read_bytes()
    assert read_plan_bytes(data).seq == 5
    assert check_signature(data, read_key(key)) == 5
    report = json.loads(Path(f"{plan}.json").read_text())
    assert report["upload"] == {"bytes": len(data), "signed": True, "seq": 5,
                                "sbd_messages": 1}  # Fig. 2's plan: under 1,890 bytes
    # the signature costs two lines: "seq 5" and "hmac" with 64 hex digits
    assert len(data) - len(unsigned_part(data)) == len("seq 5\n") + 5 + 64 + 1


def test_plan_without_sign_reports_its_upload_size(tmp_path, capsys):
    assert main(["plan", str(FIG2), "-o", str(tmp_path / "p.plan")]) == 0
    size = len((tmp_path / "p.plan").read_bytes())
    assert f"upload: {size} bytes, unsigned; 1 Iridium SBD message (1890 bytes each)" in (
        capsys.readouterr().out)
    assert main(["plan", str(FIG2), "--seq", "3"]) == 2


@pytest.mark.parametrize("runtime", ["python", "c"])
def test_sim_flies_a_signed_plan_and_fails_on_a_tampered_one(signed, tmp_path, capsys,
                                                              runtime):
    if runtime == "c" and shutil.which("cc") is None:
        pytest.skip("no C compiler (cc) to build the runtime")
    key, plan = signed
    run = ["sim", str(FIG2), "--runtime", runtime, "--key", str(key), "--plan"]
    assert main([*run, str(plan), "-o", str(tmp_path / "good")]) == 0
    assert "sampleMission: exit after 2500 s, 5 transitions" in capsys.readouterr().err
    forged = tmp_path / "forged.plan"
    forged.write_bytes(recrc(plan.read_bytes().replace(b" 0.454 ", b" 0.5 ", 1)))
    assert read_plan_bytes(forged.read_bytes()).seq == 5  # the form is right: only the tag
    assert main([*run, str(forged), "-o", str(tmp_path / "forged")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "forged.plan" in err[0]
    assert "the signature does not match" in err[0]
    assert not (tmp_path / "forged" / "summary.json").exists()
    unsigned = tmp_path / "unsigned.plan"
    unsigned.write_bytes(unsigned_part(plan.read_bytes()))
    assert main([*run, str(unsigned), "-o", str(tmp_path / "unsigned")]) == 1
    assert "the plan is not signed" in capsys.readouterr().err


def test_sign_replaces_a_signature_and_checks_the_plan(signed):
    key, plan = signed
    data = plan.read_bytes()
    again = sign_plan(data, read_key(key), 6)
    assert read_plan_bytes(again).seq == 6 and unsigned_part(again) == unsigned_part(data)
    with pytest.raises(PlanFileError, match="seq 0"):
        sign_plan(data, read_key(key), 0)
    with pytest.raises(PlanFileError):
        sign_plan(b"not a plan\n", read_key(key), 1)


@pytest.mark.parametrize(("content", "mode", "said"), [
    (None, 0o600, "no such key file"),
    ("00" * 32 + "\n", 0o644, "may be read by others (mode 644)"),
    ("00" * 31 + "\n", 0o600, "not a key file"),
    ("0G" * 32 + "\n", 0o600, "not a key file"),
], ids=["missing", "shared", "short", "not-hex"])
def test_a_bad_key_file_is_one_clear_error(tmp_path, capsys, content, mode, said):
    key = tmp_path / "k.key"
    if content is not None:
        key.write_text(content)
        key.chmod(mode)
    with pytest.raises(KeyFileError, match=re.escape(said)):
        read_key(key)


def test_a_plan_too_big_for_one_satellite_message_says_how_many_it_takes(tmp_path, capsys):
    """The month-long survey's signed plan is over 1,890 bytes: two Iridium SBD messages."""
    key = tmp_path / "k.key"
    assert main(["keygen", "-o", str(key)]) == 0
    plan = tmp_path / "month.plan"
    assert main(["plan", str(ROOT / "examples" / "survey_month.mission"), "-o", str(plan),
                 "--sign", str(key), "--seq", "1"]) == 0
    size = len(plan.read_bytes())
    assert 1890 < size <= 2 * 1890
    assert f"upload: {size} bytes, signed (seq 1); 2 Iridium SBD messages" in (
        capsys.readouterr().out)
    assert json.loads(Path(f"{plan}.json").read_text())["upload"]["sbd_messages"] == 2

"""Plan updates over the serial link to the C runtime (the hand-written Fig. 2 table, built
plain and under ASan + UBSan): applied to the same bytes planner.update makes, refused with
the same verdicts and words, stored so that a restart flies the new plan and a kill in the
middle leaves the old plan or the new one, never a mix."""

from __future__ import annotations

import random
import signal
import time
from dataclasses import replace

import test_runtime_link as link_tests
from test_runtime_link import KEY, fly, make_plan, signed

from gliderplan.contract import UpdateStatus
from gliderplan.planner.planfile import read_plan_bytes
from gliderplan.planner.signing import sign_plan
from gliderplan.planner.update import apply_update, make_updates
from gliderplan.runtime import protocol as p

OTHER_KEY = bytes(range(1, 33))
# the runtimes built plain and under the sanitizers, the pty pair, the vehicle's key
build, binary, glider, key_file = (link_tests.build, link_tests.binary, link_tests.glider,
                                   link_tests.key_file)


def update_of(held: bytes, temp_on_s: float, key: bytes = KEY, seq: int | None = None) -> bytes:
    """The update (to plan `seq`, default the next) that sets s2's temp on-time in the plan
    file `held`."""
    plan = read_plan_bytes(held)
    s2 = plan.states[1]
    target = replace(plan, states=(plan.states[0], replace(s2, sensors=(
        replace(s2.sensors[0], on_s=temp_on_s),)), plan.states[2]))
    (update,) = make_updates(held, target, key, first_seq=seq).updates
    return update


def start(glider, binary, tmp_path, key_file, *extra: str) -> p.Link:
    plan_file = tmp_path / "p.plan"
    plan_file.write_bytes(signed(3))
    glider.start(binary, "--plan", str(plan_file), "--key", key_file, "--state-dir",
                 str(tmp_path / "state"), *extra)
    link = glider.link()
    link.wait_hello()
    return link


def test_an_update_is_applied_to_the_bytes_the_shore_makes_and_flown(binary, glider,
                                                                     tmp_path, key_file):
    link = start(glider, binary, tmp_path, key_file)
    fly(link, 0, 55)  # in s2 (from 500 s), temp on for 15 s of every 60 s
    update = update_of(signed(3), 45)
    status = link.send_update(update)
    expected = apply_update(signed(3), update, KEY)
    assert (status.status, status.seq, status.message) == (UpdateStatus.APPLIED, 4,
                                                           expected.message)
    assert (tmp_path / "state" / "plan").read_bytes() == expected.plan_file
    commands = fly(link, 56, 61)  # t_in 60..110 s: on for the first 45 s of each 60 s
    assert [c.sensor_power >> 9 & 1 for c in commands] == [1, 1, 1, 1, 1, 0]
    log = (tmp_path / "state" / "plans.log").read_text().splitlines()
    assert log[-1] == "550 accepted 4 update: ok: plan 4 in force"
    glider.process.send_signal(signal.SIGTERM)
    assert "plan update over the link applied (seq 4): ok: plan 4 in force" in \
        glider.process.stderr.read()


def test_refused_updates_keep_the_plan_and_say_why_as_the_shore_would(binary, glider,
                                                                       tmp_path, key_file):
    link = start(glider, binary, tmp_path, key_file)
    fly(link, 0, 5)
    held = signed(3)
    first = update_of(held, 45)
    after_first = apply_update(held, first, KEY).plan_file
    second = update_of(after_first, 20)
    older = update_of(sign_plan(make_plan(), KEY, 2), 30, seq=5)  # against plan 2, to 5
    foreign = update_of(signed(3, s1_pitch=0.4), 30)  # against another plan 3
    cases = [
        (held, second, UpdateStatus.OUT_OF_ORDER),
        (held, update_of(held, 45, OTHER_KEY), UpdateStatus.FORGED),
        (held, first[:-1] + bytes([first[-1] ^ 1]), UpdateStatus.FORGED),
        (held, older, UpdateStatus.NOT_HELD),
        (held, update_of(sign_plan(make_plan(), KEY, 2), 30), UpdateStatus.STALE),
        (held, foreign, UpdateStatus.NOT_HELD),
        (held, b"GU" + bytes(70), UpdateStatus.MALFORMED),
        (held, b"GU\x01" + bytes(300), UpdateStatus.MALFORMED),
        (held, first, UpdateStatus.APPLIED),
        (after_first, first, UpdateStatus.DUPLICATE),
        (after_first, second, UpdateStatus.APPLIED),
        (apply_update(after_first, second, KEY).plan_file, first, UpdateStatus.STALE),
    ]
    for plan_file, update, expected in cases:
        status = link.send_update(update)
        shore = apply_update(plan_file, update, KEY)
        assert (status.status, status.message) == (expected, shore.message), shore.message
        assert status.seq == shore.seq
        assert (tmp_path / "state" / "plan").exists() == (shore.seq > 3)
        if shore.seq > 3:
            assert (tmp_path / "state" / "plan").read_bytes() == shore.plan_file
    assert [c.transition for c in fly(link, 6, 8)] == [0, 0, 0]  # flying on all along


def test_without_a_key_every_update_is_refused(binary, glider, tmp_path):
    plan_file = tmp_path / "p.plan"
    plan_file.write_bytes(make_plan())
    glider.start(binary, "--plan", str(plan_file))
    link = glider.link()
    link.wait_hello()
    status = link.send_update(update_of(signed(3), 45))
    assert status.status == UpdateStatus.NO_KEY and status.seq == 0
    assert "no key is provisioned on this vehicle" in status.message


def test_an_applied_update_outlives_a_restart_and_a_resend_is_acknowledged(
        binary, glider, tmp_path, key_file):
    link = start(glider, binary, tmp_path, key_file)
    fly(link, 0, 55)
    update = update_of(signed(3), 45)
    assert link.send_update(update).status == UpdateStatus.APPLIED
    glider.process.send_signal(signal.SIGKILL)
    glider.process.wait(5)
    link = start(glider, binary, tmp_path, key_file)  # --plan is plan 3 again
    status = link.send_update(update)  # its answer was lost: the shore sends it again
    assert (status.status, status.seq) == (UpdateStatus.DUPLICATE, 4)
    commands = fly(link, 56, 61)
    assert [c.sensor_power >> 9 & 1 for c in commands] == [1, 1, 1, 1, 1, 0]
    glider.process.send_signal(signal.SIGTERM)
    assert "flying the plan received over the link (seq 4), newer than --plan (seq 3)" in \
        glider.process.stderr.read()


def test_a_kill_during_an_update_leaves_the_old_plan_or_the_new(binary, glider, tmp_path,
                                                                key_file):
    """SIGKILL at a random moment while the update travels and is applied, 20 times: the
    stored plan is the old one (none over the link yet) or the new one, whole; the
    restarted runtime flies on from its checkpoint, and the update sent again is applied
    or acknowledged as applied."""
    rng = random.Random(5)
    update = update_of(signed(3), 45)
    new = apply_update(signed(3), update, KEY).plan_file
    outcomes = []
    for round_ in range(20):
        state = tmp_path / f"state{round_}"
        plan_file = tmp_path / "p.plan"
        plan_file.write_bytes(signed(3))
        args = ("--plan", str(plan_file), "--key", key_file, "--state-dir", str(state))
        glider.start(binary, *args)
        link = glider.link()
        link.wait_hello()
        fly(link, 0, 10)
        for piece in p.plan_pieces(update, p.UpdatePiece):
            link.send(piece)
        time.sleep(rng.uniform(0.0, 0.004))
        glider.process.kill()
        glider.process.wait(5)
        stored = state / "plan"
        applied = stored.exists()
        if applied:  # killed once the plan was stored: all of the new plan, never a part
            assert stored.read_bytes() == new
        glider.start(binary, *args)
        link = glider.link()
        link.wait_hello()
        status = link.send_update(update)
        outcomes.append(status.status)
        assert status.status in (UpdateStatus.APPLIED, UpdateStatus.DUPLICATE)
        assert (status.status == UpdateStatus.DUPLICATE) == applied
        assert stored.read_bytes() == new
        assert fly(link, 11, 12)[0].transition == 0  # resumed, not started afresh
        glider.process.kill()  # no RELEASE left on the line for the next round's link
        glider.process.wait(5)
    assert len(outcomes) == 20  # killed before the plan was stored, or after: both are fine

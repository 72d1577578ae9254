"""Plan updates (docs/plan-update.md): a signed binary delta against the plan the glider
holds, at most one short Iridium message. The shore makes them (`make_updates`), the
vehicle applies them (`apply_update`, and the C runtime over its link, to the same bytes,
with the same verdicts and words); forged, replayed, stale, out-of-order updates and
updates for a plan the glider does not hold are refused, the plan in force stays."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

from gliderplan.contract import MAX_UPDATE_BYTES, UpdateField, UpdateStatus
from gliderplan.language import check_file
from gliderplan.planner.planfile import read_plan_bytes, write_plan_bytes
from gliderplan.planner.signing import sign_plan
from gliderplan.planner.update import (
    Change,
    PlanUpdate,
    UpdateError,
    apply_update,
    changed_plan,
    decimal,
    decimal_text,
    make_updates,
    plan_hash,
    read_update,
)

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
KEY = bytes(range(32))
OTHER_KEY = bytes(range(1, 33))


@pytest.fixture(scope="module")
def survey():
    """The thermocline survey (five states, two profile alternatives) and its plan,
    signed as plan 7."""
    from gliderplan.planner import make_plan

    mission = check_file(str(EXAMPLES / "thermocline_survey.mission")).checked()
    plan = make_plan(mission).plan
    return mission, sign_plan(write_plan_bytes(plan), KEY, 7)


def _target(held: bytes, on_scale: float = 0.5, share: float | None = None):
    """The held plan with every managed sensor's on-time scaled, and the shares of a state
    with two profiles set to (share, 1 - share)."""
    plan = read_plan_bytes(held)
    states = []
    for state in plan.states:
        sensors = tuple(replace(x, on_s=round(x.on_s * on_scale, 1)) for x in state.sensors)
        profiles = state.profiles
        if share is not None and len(profiles) == 2:
            profiles = (replace(profiles[0], share=share), replace(profiles[1], share=1 - share))
        states.append(replace(state, sensors=sensors, profiles=profiles))
    return replace(plan, states=tuple(states))


@pytest.mark.parametrize("value, text", [
    (0.0, "0"), (300.0, "300"), (42.5, "42.5"), (2.5e-7, "0.00000025"), (-7.0, "-7"),
    (189.113579, "189.113579"), (0.1 + 0.2, "0.3"), (1e10, "10000000000")])
def test_a_value_travels_as_a_canonical_decimal(value, text):
    mantissa, exponent = decimal(value)
    assert decimal_text(mantissa, exponent) == text
    if value == 0:
        assert (mantissa, exponent) == (0, 0)
    else:  # no trailing zero in the mantissa: one value, one text
        assert mantissa % 10 != 0
    assert float(text) == pytest.approx(value, rel=1e-9)


def test_an_update_carries_the_duties_and_shares_and_the_vehicle_flies_the_target(survey):
    mission, held = survey
    target = _target(held, 0.5, share=0.25)
    chain = make_updates(held, target, KEY)
    assert len(chain.updates) == 1 and len(chain.updates[0]) <= MAX_UPDATE_BYTES
    applied = apply_update(held, chain.updates[0], KEY,
                           check=lambda data: read_plan_bytes(data, mission))
    assert applied.status == UpdateStatus.APPLIED and applied.seq == 8
    assert applied.plan_file == chain.plan_file
    flown = read_plan_bytes(applied.plan_file, mission)
    assert [s.sensors for s in flown.states] == [s.sensors for s in target.states]
    assert [s.profiles for s in flown.states] == [s.profiles for s in target.states]
    # the prediction and everything else the glider does not fly stays as it was
    before = read_plan_bytes(held)
    assert [s.energy_by_component_j for s in flown.states] == \
        [s.energy_by_component_j for s in before.states]
    assert flown.budget_j == before.budget_j and flown.assumptions == before.assumptions


def test_nothing_to_change_makes_no_update(survey):
    _, held = survey
    chain = make_updates(held, read_plan_bytes(held), KEY)
    assert chain.updates == () and chain.plan_file == held


def test_forged_replayed_stale_out_of_order_and_foreign_updates_are_refused(survey):
    _, held = survey
    first = make_updates(held, _target(held, 0.5), KEY)
    applied = apply_update(held, first.updates[0], KEY)
    second = make_updates(applied.plan_file, _target(held, 0.25), KEY)

    def verdict(plan_file: bytes, update: bytes, key: bytes | None = KEY):
        result = apply_update(plan_file, update, key)
        assert (result.plan_file == plan_file) is (result.status != UpdateStatus.APPLIED)
        return result.status, result.message

    assert verdict(held, first.updates[0], None)[0] == UpdateStatus.NO_KEY
    status, said = verdict(held, first.updates[0], OTHER_KEY)
    assert status == UpdateStatus.FORGED and "signed with another key" in said
    tampered = bytearray(first.updates[0])
    tampered[-40] ^= 0x01  # a change's value, after signing
    assert verdict(held, bytes(tampered))[0] in (UpdateStatus.FORGED, UpdateStatus.MALFORMED)
    tampered = bytearray(first.updates[0])
    tampered[-1] ^= 0x01
    assert verdict(held, bytes(tampered))[0] == UpdateStatus.FORGED
    # the update that made the plan in force, sent again: acknowledged, nothing changes
    status, said = verdict(applied.plan_file, first.updates[0])
    assert status == UpdateStatus.DUPLICATE and "already applied" in said
    # the second update, before the first arrived
    status, said = verdict(held, second.updates[0])
    assert status == UpdateStatus.OUT_OF_ORDER and "has not arrived" in said
    # after the second, the first again: older than the plan in force
    newest = apply_update(applied.plan_file, second.updates[0], KEY).plan_file
    status, said = verdict(newest, first.updates[0])
    assert status == UpdateStatus.STALE and "replayed or stale" in said
    # an update made against another plan 7
    other = sign_plan(write_plan_bytes(_target(held, 0.9)), KEY, 7)
    status, said = verdict(other, first.updates[0])
    assert status == UpdateStatus.NOT_HELD and "its hash differs" in said
    status, said = verdict(b"", first.updates[0])
    assert status == UpdateStatus.NOT_HELD and "no signed plan is in force" in said


def _signed_update(held: bytes, changes: tuple[Change, ...], key: bytes = KEY,
                   result: bytes | None = None) -> bytes:
    new = changed_plan(held, changes, 8, key) if result is None else result
    return PlanUpdate(7, 8, plan_hash(held), plan_hash(new), changes).pack(key)


def test_an_update_whose_plan_breaks_the_format_is_refused_naming_the_line(survey):
    mission, held = survey
    line = next(i for i, text in enumerate(held.decode().split("\n"), 1)
                if text.startswith("profile 1"))
    share = Change(line, UpdateField.PROFILE_SHARE, 9, -1)  # 0.9 beside the other's share
    result = apply_update(held, _signed_update(held, (share,)), KEY,
                          check=lambda data: read_plan_bytes(data, mission))
    assert result.status == UpdateStatus.BAD_PLAN
    assert result.message.startswith("the updated plan is refused: line ")
    assert "profile shares sum to" in result.message
    wrong = Change(line, UpdateField.SENSOR_ON, 1, 0)  # a sensor's field on a profile line
    result = apply_update(held, _signed_update(held, (wrong,), result=held), KEY)
    assert result.status == UpdateStatus.MALFORMED and "is no 'sensor' line" in result.message


@pytest.mark.parametrize("data, said", [
    (b"", "not a plan update (0 bytes)"),
    (b"XX" + bytes(100), "no GU magic"),
    (b"GU\x02" + bytes(100), "update version 2"),
    (b"GU\x01" + bytes(MAX_UPDATE_BYTES), f"more than {MAX_UPDATE_BYTES}"),
])
def test_what_is_no_update_is_refused_for_its_form(survey, data, said):
    _, held = survey
    result = apply_update(held, data, KEY)
    assert result.status == UpdateStatus.MALFORMED and said in result.message


def many_states(n: int) -> str:
    """A mission of `n` states in a row, each logging four duty-cycled sensors."""
    lines = ["mission many", "vehicle slocum_g2_shallow", "computer none",
             "battery 100 Ah at 15 V reserve 10%", "objective maximize quality",
             *(f"sensor {x} weight 1" for x in ("temp", "chlorophyll", "oxygen", "groundspeed"))]
    for i in range(n):
        after = f"goto s{i + 1}" if i + 1 < n else "exit"
        lines += [f"state s{i}", "begin", "  flightroute noheading",
                  "  flightprofile yo(3, 30, .454, .454)",
                  "  sensors missiontime, depth, temp duty auto, chlorophyll duty auto, "
                  "oxygen duty auto, groundspeed duty auto",
                  "  events", f"    case missiontime >= {3600 * (i + 1)} {after}", "end"]
    return "\n".join(lines) + "\n"


def test_changes_too_many_for_one_message_go_as_a_chain_or_are_refused_saying_what_to_cut(
        tmp_path):
    from gliderplan.planner import make_plan

    source = tmp_path / "many.mission"
    source.write_text(many_states(24))
    mission = check_file(str(source)).checked()
    held = sign_plan(write_plan_bytes(make_plan(mission, battery="90Wh").plan), KEY, 40)
    target = _target(held, 0.37)
    with pytest.raises(UpdateError, match=r"the changes take \d updates .*cut the changes "
                                          r"to s\d+ sensor"):
        make_updates(held, target, KEY)
    chain = make_updates(held, target, KEY, max_updates=8)
    assert len(chain.updates) > 1
    assert all(len(u) <= MAX_UPDATE_BYTES for u in chain.updates)
    plan_file = held
    for update in chain.updates:  # each made against the plan the one before makes
        applied = apply_update(plan_file, update, KEY, check=lambda d: read_plan_bytes(d, mission))
        assert applied.status == UpdateStatus.APPLIED
        plan_file = applied.plan_file
    assert plan_file == chain.plan_file
    assert [s.sensors for s in read_plan_bytes(plan_file).states] == \
        [s.sensors for s in target.states]


@pytest.mark.parametrize("name", sorted(p.stem for p in EXAMPLES.glob("*.mission")))
def test_every_update_of_an_example_mission_fits_one_short_message(name):
    """Whatever a replan changes (every duty the plan manages, every share), the update
    fits in 270 bytes."""
    from gliderplan.planner import make_plan

    mission = check_file(str(EXAMPLES / f"{name}.mission")).checked()
    held = sign_plan(write_plan_bytes(make_plan(mission).plan), KEY, 1_700_000_000)
    for scale, share in ((0.5123, 0.3141), (0.9876, 0.6789)):
        chain = make_updates(held, _target(held, scale, share), KEY)
        assert len(chain.updates) <= 1
        assert all(len(u) <= MAX_UPDATE_BYTES for u in chain.updates)
        if chain.updates:
            assert apply_update(held, chain.updates[0], KEY).status == UpdateStatus.APPLIED


def test_read_update_gives_back_what_was_packed(survey):
    _, held = survey
    update = make_updates(held, _target(held, 0.5, 0.75), KEY).updates[0]
    fields = read_update(update)
    assert (fields.base_seq, fields.new_seq) == (7, 8)
    assert fields.base_hash == plan_hash(held)
    assert [c.line for c in fields.changes] == sorted(c.line for c in fields.changes)
    assert PlanUpdate(fields.base_seq, fields.new_seq, fields.base_hash, fields.result_hash,
                      fields.changes).pack(KEY) == update

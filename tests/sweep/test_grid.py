"""Seeds, --set values and the order of a sweep's runs."""

from __future__ import annotations

import pytest

from fleet_async.sweep import SweepPlan, parse_assignment, parse_seeds, parse_value


def test_seeds_ranges_lists_and_single_values():
    assert parse_seeds("0:5") == [0, 1, 2, 3, 4]
    assert parse_seeds("10:20:5") == [10, 15]
    assert parse_seeds("7") == [7]
    assert parse_seeds("3, 1,2") == [3, 1, 2]


@pytest.mark.parametrize(
    ("text", "message"),
    [("a:b", "expected START:STOP"), ("5:5", "empty"), ("1,1", "twice"), ("1:2:3:4", "START")],
)
def test_bad_seeds_say_what_is_expected(text, message):
    with pytest.raises(ValueError, match=message):
        parse_seeds(text)


def test_values_are_numbers_flags_lists_or_text():
    assert parse_value("50") == 50 and isinstance(parse_value("50"), int)
    assert parse_value("0.5") == 0.5 and parse_value("1e-3") == 0.001
    assert parse_value("true") is True and parse_value("null") is None
    assert parse_value("[0, 1.5, 0.1]") == [0, 1.5, 0.1]
    assert parse_value("omni") == "omni" and parse_value("batch_omni") == "batch_omni"


def test_assignment_splits_values_outside_brackets():
    assert parse_assignment("entities.pickers.grid.count=50,100,200") == (
        "entities.pickers.grid.count",
        [50, 100, 200],
    )
    assert parse_assignment("a.pose=[0,0,0.1],[1,0,0.1]") == ("a.pose", [[0, 0, 0.1], [1, 0, 0.1]])
    for bad in ("novalue", "=1,2", "k=1,,2", "k=", "k=1,1"):
        with pytest.raises(ValueError, match="--set"):
            parse_assignment(bad)


def test_runs_are_numbered_seed_major_with_the_last_key_fastest():
    plan = SweepPlan({"a": [1, 2], "b": ["x", "y", "z"]}, seeds=[10, 20])
    runs = plan.runs()
    assert len(plan) == len(runs) == 12
    assert [r[0] for r in runs] == list(range(12))
    assert runs[0] == (0, {"a": 1, "b": "x"}, 10)
    assert runs[1] == (1, {"a": 1, "b": "y"}, 10)
    assert runs[5] == (5, {"a": 2, "b": "z"}, 10)
    assert runs[6] == (6, {"a": 1, "b": "x"}, 20)
    assert plan.run(7) == ({"a": 1, "b": "y"}, 20)


def test_more_seeds_keep_every_run_number():
    short = SweepPlan({"a": [1, 2, 3]}, seeds=range(2)).runs()
    longer = SweepPlan({"a": [1, 2, 3]}, seeds=range(5)).runs()
    assert longer[: len(short)] == short


def test_a_plan_without_a_grid_runs_each_seed_once():
    assert SweepPlan({}, seeds=[4, 5]).runs() == [(0, {}, 4), (1, {}, 5)]


def test_plan_rejects_no_seeds_and_empty_values():
    with pytest.raises(ValueError, match="seed"):
        SweepPlan({}, seeds=[])
    with pytest.raises(ValueError, match="--set a: no values"):
        SweepPlan({"a": []}, seeds=[0])
    with pytest.raises(ValueError, match="integers"):
        SweepPlan({}, seeds=[0.5])  # type: ignore[list-item]

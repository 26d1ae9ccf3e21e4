"""Ranking of the benchmark (the paper's Table 1) on hand-made records."""

import math

import pytest

from pysindy_xl.benchmark.ranking import (
    TABLE_COLUMNS,
    format_table,
    rank_trajectory,
    ranking_table,
    table_to_csv,
    table_to_markdown,
)


def rec(trajectory, config, status, rmse=None, run_time=1.0, run_id=None):
    record = {"run_id": run_id or f"{trajectory}/{config}", "trajectory_id": trajectory,
              "config": config, "status": status, "time_s": {"run": run_time}, "metrics": {}}
    if rmse is not None:
        record["metrics"]["position_rmse"] = rmse
    return record


def rows_by_config(table):
    return {row["combo type"]: row for row in table}


def test_single_winner_and_places():
    records = [rec("t", "a", "ok", 0.1), rec("t", "b", "ok", 0.2), rec("t", "c", "ok", 0.3),
               rec("t", "d", "ok", 0.4), rec("t", "e", "invalid")]
    rows = rows_by_config(ranking_table(records))
    assert [rows[c]["1st"] for c in "abcd"] == [1, 0, 0, 0]
    assert [rows[c]["2nd"] for c in "abcd"] == [0, 1, 0, 0]
    assert [rows[c]["2nd>"] for c in "abcd"] == [0, 0, 1, 1]
    assert rows["e"]["invalid"] == 1 and rows["e"]["success rate"] == 0.0
    assert all(rows[c]["Wins WC"] == 0 for c in "abcde")


def test_ties_share_the_place():
    # competition ranking: two equal errors are both 1st, the next one is 3rd (2nd>)
    ranks = rank_trajectory([rec("t", "a", "ok", 0.5), rec("t", "b", "ok", 0.5),
                             rec("t", "c", "ok", 0.7)])
    assert ranks == {"a": 1, "b": 1, "c": 3}
    rows = rows_by_config(ranking_table([rec("t", "a", "ok", 0.5), rec("t", "b", "ok", 0.5),
                                         rec("t", "c", "ok", 0.7)]))
    assert rows["a"]["1st"] == rows["b"]["1st"] == 1
    assert rows["c"]["2nd"] == 0 and rows["c"]["2nd>"] == 1
    # a tie for second place: errors equal within 0.1 % (the same model, integration noise)
    ranks = rank_trajectory([rec("t", "a", "ok", 0.1), rec("t", "b", "ok", 0.2),
                             rec("t", "c", "ok", 0.2 * (1 + 1e-6))])
    assert ranks == {"a": 1, "b": 2, "c": 2}
    # no chaining: each within 0.1 % of its neighbour, but the last is 0.16 % above the best
    ranks = rank_trajectory([rec("t", "a", "ok", 1.0), rec("t", "b", "ok", 1.0008),
                             rec("t", "c", "ok", 1.0016), rec("t", "d", "ok", 1.01)])
    assert ranks == {"a": 1, "b": 1, "c": 3, "d": 4}


def test_all_invalid_trajectory_gives_no_place():
    records = [rec("t", "a", "invalid"), rec("t", "b", "timeout"), rec("t", "c", "error")]
    rows = rows_by_config(ranking_table(records))
    assert rank_trajectory(records) == {}
    for config in "abc":
        assert rows[config]["1st"] == rows[config]["2nd"] == rows[config]["Wins WC"] == 0
    assert (rows["a"]["invalid"], rows["b"]["timeout"], rows["c"]["uncompleted"]) == (1, 1, 1)
    # timeouts are out of the success-rate denominator: nothing counted -> undefined
    assert math.isnan(rows["b"]["success rate"])
    assert rows["a"]["success rate"] == rows["c"]["success rate"] == 0.0


def test_wins_without_competition():
    records = [
        rec("t1", "a", "ok", 0.3), rec("t1", "b", "invalid"), rec("t1", "c", "timeout"),
        rec("t2", "a", "ok", 0.3), rec("t2", "b", "ok", 0.1),
        rec("t3", "b", "ok", 2.0),  # b alone on a trajectory a did not run: also without rivals
    ]
    rows = rows_by_config(ranking_table(records))
    assert rows["a"]["Wins WC"] == 1 and rows["a"]["1st"] == 1 and rows["a"]["2nd"] == 1
    assert rows["b"]["Wins WC"] == 1 and rows["b"]["1st"] == 2 and rows["b"]["invalid"] == 1
    assert rows["c"]["timeout"] == 1


def test_success_rate_reproduces_the_papers_table():
    # Rows of the paper's Table 1: (invalid, timeout, uncompleted, 1st, 2nd, 2nd>) -> rate.
    paper = {
        "mixed x mixed (our)": ((25, 0, 20, 59, 12, 0), 0.612069),
        "sindy x mixed": ((81, 43, 11, 12, 8, 0), 0.178571),
        "xlsindy x mixed": ((59, 0, 43, 3, 6, 4), 0.113043),
        "mixed x implicit (our)": ((1, 0, 1, 10, 2, 2), 0.875000),
    }
    for config, ((invalid, timeout, uncompleted, first, second, worse), rate) in paper.items():
        records, k = [], 0
        for status, count in (("invalid", invalid), ("timeout", timeout),
                              ("error", uncompleted)):
            for _ in range(count):
                records.append(rec(f"x{k}", config, status))
                k += 1
        for place, count in ((1, first), (2, second), (3, worse)):
            for _ in range(count):
                # `place - 1` better rivals on a trajectory of its own
                records += [rec(f"x{k}", f"rival{j}", "ok", 0.1 * (j + 1))
                            for j in range(place - 1)]
                records.append(rec(f"x{k}", config, "ok", 10.0))
                k += 1
        row = rows_by_config(ranking_table(records))[config]
        assert (row["invalid"], row["timeout"], row["uncompleted"], row["1st"], row["2nd"],
                row["2nd>"]) == (invalid, timeout, uncompleted, first, second, worse)
        assert row["success rate"] == pytest.approx(rate, abs=5e-7)


def test_sorted_by_first_places_then_success_rate_and_zero_rows():
    records = [rec("t1", "a", "ok", 0.2), rec("t1", "b", "ok", 0.1),
               rec("t2", "a", "ok", 0.2), rec("t2", "b", "ok", 0.1), rec("t3", "a", "ok", 1.0),
               rec("t3", "c", "invalid")]
    table = ranking_table(records, configs=["a", "b", "c", "never-ran"])
    assert [row["combo type"] for row in table] == ["b", "a", "c", "never-ran"]
    assert table[-1]["runs"] == 0 and math.isnan(table[-1]["success rate"])
    assert table[1]["median RMSE"] == pytest.approx(0.2)


def test_latest_record_of_a_run_wins():
    records = [rec("t", "a", "error", run_id="r"), rec("t", "b", "ok", 0.5),
               rec("t", "a", "ok", 0.1, run_id="r")]
    rows = rows_by_config(ranking_table(records))
    assert rows["a"]["uncompleted"] == 0 and rows["a"]["1st"] == 1 and rows["a"]["runs"] == 1


def test_bad_records_are_rejected():
    with pytest.raises(ValueError, match="status"):
        ranking_table([rec("t", "a", "done", 0.1)])
    with pytest.raises(ValueError, match="position_rmse"):
        ranking_table([rec("t", "a", "ok")])
    with pytest.raises(ValueError, match="twice"):
        rank_trajectory([rec("t", "a", "ok", 0.1, run_id="1"), rec("t", "a", "ok", 0.2,
                                                                     run_id="2")])


def test_text_markdown_and_csv_formats():
    table = ranking_table([rec("t", "mixed x mixed", "ok", 0.1), rec("t", "b", "invalid")])
    text = format_table(table)
    assert text.splitlines()[0].split()[:2] == ["combo", "type"]
    assert "1.000000" in text.splitlines()[1]
    markdown = table_to_markdown(table)
    assert markdown.count("\n") == 4 and markdown.startswith("| combo type |")
    csv_lines = table_to_csv(table).splitlines()
    assert csv_lines[0].split(",")[: len(TABLE_COLUMNS)] == list(TABLE_COLUMNS)
    assert csv_lines[1].startswith("mixed x mixed,0,0,0,1,0,0,1,1.0")

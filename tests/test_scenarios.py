"""Scenario records: CSV round trip, clear errors on bad files, shortest paths that make sense."""

import csv
import math

import pytest

from egosearch.scene.layouts import get_scene
from egosearch.scene.placement import rests_on_support
from egosearch.sim.scenarios import (
    COLUMNS,
    SUCCESS_DISTANCE,
    ScenarioFileError,
    generate_scenarios,
    read_scenarios,
    write_scenarios,
)


@pytest.fixture(scope="module")
def scenarios():
    return generate_scenarios("bedroom_bath", "everywhere", 1.65, n=8, seed=3)


def test_generation_is_reproducible_and_valid(scenarios):
    assert scenarios == generate_scenarios("bedroom_bath", "everywhere", 1.65, n=8, seed=3)
    assert scenarios != generate_scenarios("bedroom_bath", "everywhere", 1.65, n=8, seed=4)
    scene = get_scene("bedroom_bath")
    for sc in scenarios:
        assert rests_on_support(scene, sc.target()) is not None
        # A geodesic is never shorter than the straight line to the success disc.
        straight = math.hypot(sc.target_x - sc.start_x, sc.target_y - sc.start_y) - SUCCESS_DISTANCE - 0.2
        assert sc.shortest_path >= straight - 0.1


def test_csv_round_trip(tmp_path, scenarios):
    path = tmp_path / "s.csv"
    write_scenarios(path, scenarios)
    assert read_scenarios(path) == scenarios


def _rewrite(path, mutate):
    rows = list(csv.DictReader(open(path)))
    header = list(rows[0])
    rows, header = mutate(rows, header)
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=header)
        writer.writeheader()
        writer.writerows(rows)


def test_missing_column_is_named(tmp_path, scenarios):
    path = tmp_path / "s.csv"
    write_scenarios(path, scenarios)
    _rewrite(path, lambda rows, h: ([{k: v for k, v in r.items() if k != "height"} for r in rows],
                                    [c for c in h if c != "height"]))
    with pytest.raises(ScenarioFileError, match="missing columns height"):
        read_scenarios(path)


@pytest.mark.parametrize("field, value, message", [
    ("start_x", "abc", "start_x='abc' is not a valid float"),
    ("scenario_id", "1.5", "scenario_id='1.5' is not a valid int"),
    ("layout", "garage", "garage"),
    ("placement", "under_the_sofa", "placement='under_the_sofa'"),
    ("height", "9.0", "height=9.0"),
    ("target_object", "piano", "piano"),
    ("target_y", "nan", "not finite"),
    # nonsense that used to be scored: a failure with path 0, an SPL of 1, two episodes joined as one
    ("start_x", "500", "start (500, "),
    ("target_y", "-30", "is outside the home bedroom_bath"),
    ("shortest_path", "-1.5", "shortest_path=-1.5 is negative"),
    ("scenario_id", "0", "scenario_id=0 repeats the id of line 2"),
])
def test_malformed_value_is_one_line_naming_the_row(tmp_path, scenarios, field, value, message):
    path = tmp_path / "s.csv"
    write_scenarios(path, scenarios)

    def spoil(rows, header):
        rows[2][field] = value
        return rows, header

    _rewrite(path, spoil)
    with pytest.raises(ScenarioFileError) as err:
        read_scenarios(path)
    text = str(err.value)
    assert message in text and ":4:" in text and "\n" not in text


def test_write_is_atomic(tmp_path, scenarios):
    path = tmp_path / "s.csv"
    write_scenarios(path, scenarios)
    assert not list(tmp_path.glob("*.tmp"))
    assert open(path).readline().strip().split(",") == list(COLUMNS)


def test_bad_generation_arguments():
    with pytest.raises(ValueError, match="height=0.1"):
        generate_scenarios("kitchen_living", "everywhere", 0.1, n=1, seed=0)
    with pytest.raises(ValueError, match="placement='nowhere'"):
        generate_scenarios("kitchen_living", "nowhere", 1.0, n=1, seed=0)

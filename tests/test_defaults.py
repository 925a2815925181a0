"""One source per parameter: the workflow's schema, the CLI and the library agree."""

from __future__ import annotations

import inspect
import json
from pathlib import Path

import pytest

from slipwave import defaults
from slipwave.cli import build_parser
from slipwave.events import detect_events, edge_jumps, load_drops
from slipwave.solver import LoadPath, Slab
from slipwave.video import kymograph

SCHEMA = json.loads(
    (Path(__file__).parents[1] / "workflow/schemas/config.schema.json").read_text())

# config key -> (the library's default, the CLI subcommand and its option's dest)
WORKFLOW_PARAMETERS = {
    ("detection", "threshold"): (defaults.THRESHOLD, "detect", "threshold"),
    ("detection", "max_spike"): (defaults.MAX_SPIKE, "detect", "max_spike"),
    ("detection", "max_duration"): (defaults.MAX_DURATION_S, "detect", "max_duration"),
    ("detection", "min_fall_rate"): (defaults.MIN_FALL_RATE, "detect", "min_fall_rate"),
    ("detection", "gross_edge_ratio"): (defaults.GROSS_EDGE_RATIO, "detect", "gross_edge_ratio"),
    ("detection", "edge_convention"): (defaults.EDGE_CONVENTION, "detect", "edge_convention"),
    ("video", "length_mm"): (defaults.CONTACT_LENGTH_MM, "kymograph", "length"),
    ("fit", "laws"): (list(defaults.FIT_LAWS), "fit", "laws"),
    ("fit", "elements"): (defaults.FIT_ELEMENTS, "fit", "elements"),
    ("fit", "max_evaluations"): (defaults.FIT_MAX_EVALUATIONS, "fit", "max_evaluations"),
    ("fit", "load_calibration"): (defaults.LOAD_CALIBRATION, "fit", "load_calibration"),
    ("video", "band_mm"): (list(defaults.BAND_MM), "kymograph", "band"),
}


def _cli_default(command: str, dest: str) -> object:
    parser = build_parser()
    commands = next(a for a in parser._actions if a.dest == "command")
    sub = commands.choices[command]  # type: ignore[index]
    return next(a.default for a in sub._actions if a.dest == dest)


@pytest.mark.parametrize(("section", "key"), list(WORKFLOW_PARAMETERS))
def test_schema_cli_and_library_defaults_agree(section, key):
    value, command, dest = WORKFLOW_PARAMETERS[(section, key)]
    assert SCHEMA["properties"][section]["properties"][key]["default"] == value
    assert _cli_default(command, dest) == value


def test_every_schema_default_is_listed():
    listed = {(s, k) for s, k in WORKFLOW_PARAMETERS}
    for section in ("detection", "video"):
        for key in SCHEMA["properties"][section]["properties"]:
            assert (section, key) in listed


def test_library_signatures_take_the_defaults():
    for function in (detect_events, load_drops, edge_jumps):
        parameters = inspect.signature(function).parameters
        assert parameters["threshold"].default == defaults.THRESHOLD
        assert parameters["max_spike"].default == defaults.MAX_SPIKE
        assert parameters["max_duration"].default == defaults.MAX_DURATION_S
    assert inspect.signature(detect_events).parameters["gross_edge_ratio"].default == \
        defaults.GROSS_EDGE_RATIO
    assert inspect.signature(kymograph).parameters["band_mm"].default == defaults.BAND_MM
    slab = Slab()
    assert (slab.length, slab.height, slab.width, slab.youngs_modulus, slab.poisson_ratio,
            slab.elements) == (defaults.CONTACT_LENGTH_MM, defaults.SLAB_HEIGHT_MM,
                               defaults.SLAB_WIDTH_MM, defaults.YOUNGS_MODULUS_MPA,
                               defaults.POISSON_RATIO, defaults.CONTACT_ELEMENTS)
    path = LoadPath()
    assert (path.normal_load, path.tangential_step) == (defaults.NORMAL_LOAD_N,
                                                         defaults.TANGENTIAL_STEP_N)
    assert _cli_default("simulate", "height") == defaults.SLAB_HEIGHT_MM
    assert _cli_default("simulate", "normal_load") == defaults.NORMAL_LOAD_N


def test_map_defaults_agree():
    """The map's config section, `slipwave map row` and slipwave.map take one default each."""
    from slipwave.map import PAPER_HEIGHT_RATIOS, map_row
    from slipwave.solver.behaviour import describe_behaviour

    schema = SCHEMA["properties"]["map"]["properties"]
    commands = next(a for a in build_parser()._actions if a.dest == "command")
    steps = next(a for a in commands.choices["map"]._actions  # type: ignore[index]
                 if a.dest == "map_command")
    row = {a.dest: a.default for a in steps.choices["row"]._actions}  # type: ignore[index]
    assert schema["elements"]["default"] == row["elements"] == defaults.CONTACT_ELEMENTS
    assert schema["normal_control"]["default"] == row["normal_control"] == \
        defaults.MAP_NORMAL_CONTROL
    assert schema["normal_friction"]["default"] is defaults.MAP_NORMAL_FRICTION is False
    assert row["normal_friction"] == "off"
    assert schema["min_zone_mm"]["default"] == row["min_zone"] == defaults.MIN_ZONE_MM
    assert schema["frictions"]["default"] == row["frictions"] == [0.10, 1.40, 0.01]
    assert tuple(schema["height_ratios"]["default"]) == PAPER_HEIGHT_RATIOS
    assert inspect.signature(map_row).parameters["min_size"].default == defaults.MIN_ZONE_MM
    assert inspect.signature(describe_behaviour).parameters["min_size"].default == \
        defaults.MIN_ZONE_MM
    assert inspect.signature(map_row).parameters["elements"].default == defaults.CONTACT_ELEMENTS

"""One settings path: each config key reaches exactly the stages that use it.

Each key of the campaign config is changed in turn and the workflow's jobs are listed
(a forced dry run): the rules whose command changes are the stages the setting reaches,
and Snakemake reruns them and what follows from their products. The command's options
then reach the library's functions (the library tests), and ``fit.json`` records the
detection it used.
"""

from __future__ import annotations

import re
import shutil
from collections import defaultdict
from pathlib import Path

import pytest

from dry_runs import SnakemakeRunner
from slipwave.cli import build_parser
from slipwave.events import DetectionSettings

ROOT = Path(__file__).parents[1]

DETECTING = {"detect", "fit", "simulate", "compare"}
# config key (section, key, a value other than the default) -> the rules it reaches
REACHES = [
    ("detection", "threshold", 10.0, DETECTING),
    ("detection", "max_spike", 3, DETECTING),
    ("detection", "max_duration", 5.0, DETECTING),
    ("detection", "min_fall_rate", 1.5, DETECTING),
    ("detection", "edge_convention", "outward", DETECTING),
    # each test's threshold comes from its simulation: the config's is not used
    ("detection", "gross_edge_ratio", 1.2, set()),
    ("video", "length_mm", 90.0, {"kymograph"}),
    ("video", "band_mm", [0.5, 3.0], {"kymograph", "simulate"}),
    ("fit", "laws", ["coulomb"], {"fit"}),
    ("fit", "elements", 60, {"fit"}),
    ("fit", "members", 5, {"fit"}),
    ("fit", "stiffness_error", 0.03, {"fit"}),
    ("fit", "speed_error", 0.003, {"fit"}),
    ("fit", "step_jitter", 0.1, {"fit"}),
    ("fit", "ratio_error", 0.004, {"fit"}),
    ("fit", "time_error_s", 0.2, {"fit"}),
    ("fit", "design", 3, {"fit"}),
    ("fit", "refinements", 2, {"fit"}),
    ("fit", "draw_temperature", 2.0, {"fit"}),
    ("fit", "samples", 1000, {"fit"}),
    ("fit", "predictive_members", 8, {"fit"}),
    ("fit", "seed", 7, {"fit"}),
    ("fit", "load_calibration", 0.01, {"fit"}),
    ("fit", "mesh_check", False, {"fit"}),
    ("simulate_waves", "a", 0.012, {"simulate_waves"}),
    ("simulate_waves", "b", 0.02, {"simulate_waves"}),
    ("simulate_waves", "dc_um", 3.0, {"simulate_waves"}),
    ("simulate_waves", "mu0", 0.8, {"simulate_waves"}),
    ("simulate_waves", "v0_um_s", 2.0, {"simulate_waves"}),
    ("simulate_waves", "elements", 160, {"simulate_waves"}),
    ("simulate_waves", "field_rate_hz", 20.0, {"simulate_waves"}),
    # the rows' paths name their mesh: the assembly's command changes with it
    ("map", "elements", 640, {"map_row", "map_assemble"}),
    ("map", "band_elements", 80, {"map_row", "map_assemble"}),
    ("map", "band_steps", 1, {"map_assemble"}),
    ("map", "frictions", [0.2, 1.4, 0.02], {"map_row"}),
    ("map", "normal_control", "displacement", {"map_row"}),
    ("map", "normal_friction", True, {"map_row"}),
    ("map", "min_zone_mm", 2.0, {"map_row"}),
    ("map", "mem_mb", 2000, {"map_row"}),
    # where the jobs keep condensations: Snakemake reruns them (a param), with the same
    # products
    (None, "cache_dir", "elsewhere", {"fit", "simulate", "map_row", "map_figures"}),
]
pytestmark = [pytest.mark.workflow, pytest.mark.slow]


def _yaml(value: object) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, list):
        return "[" + ", ".join(str(v) for v in value) + "]"
    return str(value)


def commands(snakemake_cli: SnakemakeRunner, workdir: Path, extra: str = ""
             ) -> dict[str, list[str]]:
    """Every rule's shell commands in a forced dry run, with ``extra`` config appended."""
    override = workdir / "override.yaml"
    override.write_text(extra or "{}\n")
    run = snakemake_cli(workdir, "-n", "-F", "-p", "--cores", "2", "--configfile",
                        "config/config.yaml", str(override))
    assert run.returncode == 0, run.stdout + run.stderr
    found: dict[str, list[str]] = defaultdict(list)
    rule = ""
    for line in run.stdout.splitlines():
        if match := re.match(r"^\s*(?:local)?rule (\w+):", line):
            rule = match.group(1)
        elif line.strip().startswith("Shell command: "):
            found[rule].append(line.strip().removeprefix("Shell command: "))
    return {name: sorted(lines) for name, lines in found.items()}


@pytest.fixture(scope="module")
def workdir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("settings")
    for name in ["Snakefile", "workflow", "config", "raw_data"]:
        source = ROOT / name
        (shutil.copytree if source.is_dir() else shutil.copy)(source, folder / name)
    return folder


@pytest.fixture(scope="module")
def default_commands(snakemake_cli: SnakemakeRunner, workdir: Path) -> dict[str, list[str]]:
    return commands(snakemake_cli, workdir)


@pytest.mark.parametrize(("section", "key", "value", "rules"), REACHES,
                         ids=[f"{s}.{k}" if s else k for s, k, _, _ in REACHES])
def test_a_setting_reaches_exactly_the_stages_that_use_it(snakemake_cli, workdir,
                                                          default_commands, section, key,
                                                          value, rules):
    extra = (f"{section}:\n  {key}: {_yaml(value)}\n" if section
             else f"{key}: {_yaml(value)}\n")
    changed = commands(snakemake_cli, workdir, extra)
    assert set(changed) == set(default_commands)
    assert {name for name in changed if changed[name] != default_commands[name]} == rules


def test_without_quasi_dynamic_runs_compare_takes_no_simulated_waves(snakemake_cli, workdir):
    off = commands(snakemake_cli, workdir, "simulate_waves:\n  enabled: false\n")
    assert "simulate_waves" not in off
    assert not any("--simulated-waves" in line for line in off["compare"])
    on = commands(snakemake_cli, workdir)
    filmed = [line for line in on["compare"] if "--waves" in line]
    assert filmed and all("--simulated-waves" in line for line in filmed)
    assert len(on["simulate_waves"]) == len(filmed)


FIT_WAVES_ON = "fit_waves:\n  enabled: true\n"
# each fit_waves key at another value than its default, and the option it becomes
FIT_WAVES_CHANGED = {"elements": (60, "--elements 60"), "members": (3, "--members 3"),
                     "design": (5, "--design 5"), "refinements": (2, "--refinements 2"),
                     "samples": (500, "--samples 500"), "mesh_checks": (1, "--mesh-checks 1"),
                     "seed": (7, "--seed 7")}


def test_the_rate_and_state_fit_runs_the_filmed_tests_under_their_fitted_law(
        snakemake_cli, workdir, default_commands):
    on = commands(snakemake_cli, workdir, FIT_WAVES_ON)
    assert "fit_waves" not in default_commands
    filmed = [line for line in default_commands["compare"] if "--waves" in line]
    assert len(on["fit_waves"]) == len(filmed) == len(on["simulate_waves"])
    # each test's run takes its own fit's law, in place of the config's; its page shows it
    for line in on["simulate_waves"]:
        test_id = re.search(r"results/(\w+)/fit\.json", line).group(1)
        assert f"--law-fit results/{test_id}/fit_waves.json" in line and "--dc-um" not in line
    assert sum("--waves-fit" in line for line in on["report"]) == len(filmed)
    changed = {name for name in on if on[name] != default_commands.get(name)}
    assert changed == {"fit_waves", "simulate_waves", "report"}
    # the fit detects slips as every other stage does
    detecting = commands(snakemake_cli, workdir, FIT_WAVES_ON + "detection:\n  threshold: 10\n")
    assert all("--threshold 10" in line for line in detecting["fit_waves"])
    # each of its settings reaches it alone, as the option of its name
    settings = "".join(f"  {key}: {value}\n" for key, (value, _) in FIT_WAVES_CHANGED.items())
    tuned = commands(snakemake_cli, workdir, FIT_WAVES_ON + settings)
    assert {name for name in tuned if tuned[name] != on[name]} == {"fit_waves"}
    for _, option in FIT_WAVES_CHANGED.values():
        assert all(option in line for line in tuned["fit_waves"])


def test_without_fits_the_gross_edge_ratio_reaches_detection_alone(snakemake_cli, workdir):
    unfitted = "fit:\n  enabled: false\n"
    before = commands(snakemake_cli, workdir, unfitted)
    after = commands(snakemake_cli, workdir, unfitted + "detection:\n  gross_edge_ratio: 1.2\n")
    assert {name for name in after if after[name] != before.get(name)} == {"detect"}
    assert all("--gross-edge-ratio 1.2" in line for line in after["detect"])


def test_every_schema_setting_is_tried():
    from slipwave.validation import load_schema

    schema = load_schema("config")["properties"]
    tried = {(s, k) for s, k, _, _ in REACHES}
    tried |= {("fit_waves", key) for key in FIT_WAVES_CHANGED}
    untried = {("map", "height_ratios"), ("map", "row_jobs"), ("map", "shard_size"),
               ("fit", "enabled"), ("simulate_waves", "enabled"),
               ("fit_waves", "enabled")}  # jobs
    for section in ("detection", "video", "fit", "simulate_waves", "fit_waves", "map"):
        for key in schema[section]["properties"]:
            assert (section, key) in tried | untried, f"{section}.{key} is not tried"


@pytest.mark.parametrize("command", ["detect", "fit", "simulate", "compare", "fit-waves"])
def test_every_detecting_command_takes_the_detection_settings(command, tmp_path,
                                                               monkeypatch):
    monkeypatch.chdir(tmp_path)  # the inputs the options name must exist
    for name in ("r.nc", "e.nc", "s.nc", "fit.json", "w.csv", "k.nc"):
        (tmp_path / name).write_text("")
    arguments = {"detect": ["detect", "r.nc", "-o", "e.csv"],
                 "fit": ["fit", "r.nc", "-o", "fit.json"],
                 "simulate": ["simulate", "--fit", "fit.json", "-o", "s.nc"],
                 "compare": ["compare", "e.nc", "--simulated", "s.nc", "--fit", "fit.json",
                             "-o", "c.csv"],
                 "fit-waves": ["fit-waves", "--fit", "fit.json", "--recording", "r.nc",
                               "--waves", "w.csv", "--kymograph", "k.nc", "-o", "f.json"]
                 }[command]
    args = build_parser().parse_args([*arguments, "--threshold", "11", "--max-spike", "4",
                                      "--max-duration", "6", "--min-fall-rate", "1.7",
                                      "--edge-convention", "outward"])
    # each option lands on the setting of its name
    given = DetectionSettings(threshold=11.0, max_spike=4, max_duration=6.0,
                              min_fall_rate=1.7, edge_convention="outward")
    assert DetectionSettings(**{name: getattr(args, name) for name in given.to_dict()}) == given

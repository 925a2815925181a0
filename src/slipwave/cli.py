"""The ``slipwave`` command: one entry point, a subcommand per stage.

A thin layer: argument parsing, then calls into the package. Each workflow stage
has one name for its rule, its ``workflow/rules/<stage>.smk``, its subcommand and
its module: ingest (:mod:`slipwave.io.ingest`), detect (:mod:`slipwave.events.detect`),
summary (:mod:`slipwave.events.summary`), kymograph (:mod:`slipwave.video.kymograph`),
waves (:mod:`slipwave.video.waves`), fit (:mod:`slipwave.fit`), fits
(:mod:`slipwave.fits`), simulate (:mod:`slipwave.simulate`), compare
(:mod:`slipwave.compare`), map_row, map_assemble and map_figures (:mod:`slipwave.map`),
report (:mod:`slipwave.report`) and campaign_report (:mod:`slipwave.campaign_report`).
Defaults come from :mod:`slipwave.defaults`.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import threading
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from slipwave import __version__
from slipwave import defaults as default
from slipwave.errors import SlipwaveError, warning_lines

if TYPE_CHECKING:
    from slipwave.events import DetectionSettings
    from slipwave.solver import SolverCache


def _column_pair(text: str) -> tuple[str, str]:
    header, equals, channel = text.rpartition("=")
    if not equals or not header:
        raise argparse.ArgumentTypeError(f"expected NAME=CHANNEL, got {text!r}")
    return header, channel


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError as err:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from err
    if not value > 0:
        raise argparse.ArgumentTypeError(f"must be positive, got {text}")
    return value


def _non_negative_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError as err:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from err
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be 0 or more, got {text}")
    return value


def _positive_int(text: str) -> int:
    value = _non_negative_int(text)
    if value == 0:
        raise argparse.ArgumentTypeError("must be 1 or more, got 0")
    return value


def _input(text: str) -> Path:
    """An input file or folder that exists (said before anything runs)."""
    path = Path(text)
    if not path.exists():
        raise argparse.ArgumentTypeError(f"no such file or folder: {text!r}")
    return path


def _setting(section: str, key: str) -> Callable[[str], float | int]:
    """An option's type checked against the config schema's ``section.key``.

    The same bounds on the command line as in a campaign's config.
    """
    import jsonschema

    schema = default.setting_schema(section, key)
    schema.pop("default", None)
    integer = schema.get("type") == "integer"

    def convert(text: str) -> float | int:
        try:
            value: float | int = int(text) if integer else float(text)
        except ValueError as err:
            kind = "a whole number" if integer else "a number"
            raise argparse.ArgumentTypeError(f"expected {kind}, got {text!r}") from err
        try:
            jsonschema.validate(value, schema)
        except jsonschema.ValidationError as err:
            raise argparse.ArgumentTypeError(f"{err.message} (the config's {section}.{key} "
                                             "takes the same values)") from err
        return value

    convert.__name__ = f"{section}.{key}"  # argparse names the type in its messages
    return convert


def _band(values: Sequence[float], option: str = "--band") -> tuple[float, float]:
    """A band above the interface, mm: two numbers, 0 <= low < high."""
    low, high = values
    if not 0 <= low < high:
        raise SlipwaveError(f"{option} {low:g} {high:g}: a band above the interface needs "
                            "0 <= LOW < HIGH, mm")
    return low, high


def _optional_float(text: str) -> float | None:
    if text.lower() == "none":
        return None
    try:
        return float(text)
    except ValueError as err:
        raise argparse.ArgumentTypeError(f"expected a number or 'none', got {text!r}") from err


def _detection_settings(args: argparse.Namespace) -> DetectionSettings:
    """The detection's settings of a command's options (:func:`_detection_options`)."""
    from slipwave.events import DetectionSettings

    return DetectionSettings(threshold=args.threshold, max_spike=args.max_spike,
                             max_duration=args.max_duration, min_fall_rate=args.min_fall_rate,
                             edge_convention=args.edge_convention)


def _solver_cache(args: argparse.Namespace) -> SolverCache:
    """The process's solver cache, keeping condensations in ``--cache-dir`` if given."""
    from slipwave.cache import DiskCache
    from slipwave.solver import SolverCache

    return SolverCache(None if args.cache_dir is None else DiskCache(args.cache_dir))


def _print_warnings(source: object, attrs: Mapping[Any, Any]) -> None:
    for warning in warning_lines(attrs):
        print(f"warning: {source}: {warning}", file=sys.stderr)


def _ingest(args: argparse.Namespace) -> None:
    from slipwave.identity import test_id_problem
    from slipwave.io import read_acquisition, write_dataset

    recording = read_acquisition(args.raw, columns=dict(args.columns) or None)
    if args.test_id is not None:
        recording.attrs["test_id"] = args.test_id
    problem = test_id_problem(recording.attrs["test_id"])
    if problem is not None:
        where = "--test-id" if args.test_id is not None else f"{args.raw}: header line test_id"
        raise SlipwaveError(f"{where}: {problem}; name the test with --test-id")
    write_dataset(recording, args.output)
    _print_warnings(args.raw, recording.attrs)
    print(f"{args.raw} -> {args.output}: {recording.sizes['time']} samples")


def _detect(args: argparse.Namespace) -> None:
    from slipwave.events import detect_events, events_dataset, segment_phases, wave_counts
    from slipwave.identity import check_same_test, stamp
    from slipwave.io import read_dataset, write_dataset, write_table

    recording = read_dataset(args.recording, "recording")
    ratio = args.gross_edge_ratio
    if args.simulated is not None:
        simulated = read_dataset(args.simulated, "simulated recording")
        check_same_test([(args.recording, recording.attrs), (args.simulated, simulated.attrs)])
        if "gross_edge_ratio" not in simulated.attrs:
            raise SlipwaveError(f"{args.simulated}: no gross_edge_ratio: not a recording of "
                                "'slipwave simulate --fit'")
        ratio = float(simulated.attrs["gross_edge_ratio"])
        print(f"gross/partial edge threshold from the simulation: {ratio:.3g}")
    events = detect_events(recording, **_detection_settings(args).keywords(
        min_drop=args.min_drop, min_jump=args.min_jump, gross_edge_ratio=ratio))
    dataset = events_dataset(events, segment_phases(recording, events))
    stamp(dataset.attrs, "events", recording.attrs)
    dataset.attrs["source"] = str(args.recording)
    if args.netcdf is not None:
        write_dataset(dataset, args.netcdf)
    write_table(events, args.output, dataset.attrs)
    _print_warnings(args.recording, events.attrs)
    counts = ", ".join(f"{n} {kind}" for kind, n in wave_counts(events).items())
    print(f"{args.recording} -> {args.output}: {len(events)} events ({counts})")


def _setting_pair(text: str) -> tuple[str, str]:
    key, equals, value = text.partition("=")
    if not equals or not key:
        raise argparse.ArgumentTypeError(f"expected COLUMN=VALUE, got {text!r}")
    return key, value


def _fit(args: argparse.Namespace) -> None:
    import json

    from slipwave.fit import FitSettings, fit_test, measured_events
    from slipwave.identity import stamp
    from slipwave.io import atomic_output, read_dataset
    from slipwave.resources import require_memory
    from slipwave.setup import read_test_setup

    recording = read_dataset(args.recording, "recording")
    cells = {**dict(args.setting), "test_id": str(recording.attrs["test_id"])}
    detection = _detection_settings(args)
    events = measured_events(recording, detection=detection)
    setup = read_test_setup(recording, cells)
    check_mesh = args.mesh_check == "on"
    finest = 2 * args.elements if check_mesh else args.elements
    require_memory(setup.simulation_memory(finest, float(events.attrs["sample_rate"])),
                   f"fitting test {setup.test_id!r} with {args.elements} elements"
                   + (f" (checked at {finest})" if check_mesh else ""),
                   limit_gb=args.memory_limit)
    settings = FitSettings.from_values({**vars(args), "mesh_check": check_mesh})
    fit = fit_test(setup, events, settings, laws=args.laws, detection=detection,
                   cache=_solver_cache(args))
    stamp(fit, None, recording.attrs)
    seconds = {law: entry.pop("seconds") for law, entry in fit["laws"].items()}
    finer = fit["mesh_check"]
    if finer is not None:
        seconds["mesh_check"] = finer.pop("seconds")
    with atomic_output(args.output) as temporary:  # (wall times to the log only)
        temporary.write_text(json.dumps(fit, indent=2), encoding="utf-8")
    for law, entry in fit["laws"].items():
        values = ", ".join(f"{name} {p['value']:.4g} [{p['low']:.4g}, {p['high']:.4g}]"
                           for name, p in entry["parameters"].items())
        print(f"{law}: {values}; log evidence {entry['log_evidence']:.1f} (Bayes factor "
              f"e^{entry['log_bayes_factor']:.1f}){' (rejected)' if entry['rejected'] else ''}, "
              f"{entry['guesses']} guesses, {entry['simulations']} simulations in "
              f"{seconds[law]:.0f} s")
    differs = [name for name, check in fit["predictive"].items() if not check["agrees"]]
    print(f"{fit['chosen']} chosen ({fit['chosen_because']}); its posterior predictive "
          + (f"differs on {', '.join(differs)}" if differs else "agrees on every feature"))
    if finer is not None:
        changes = ", ".join(f"{name} {change:+.2%}" for name, change in finer["change"].items())
        print(f"{finer['law']} searched at {finer['elements']} elements: {changes}; "
              f"{finer['simulations']} simulations in {seconds['mesh_check']:.0f} s")
    print(f"{args.recording} -> {args.output}: {fit['chosen']}")


def _compare(args: argparse.Namespace) -> None:
    import json

    from slipwave.compare import compare_test, place_on_map, verdict_counts
    from slipwave.events import events_table
    from slipwave.fit import chosen_law, read_fit
    from slipwave.identity import check_same_test
    from slipwave.io import atomic_output, read_dataset, read_table, write_table
    from slipwave.simulate import left_out_neighbours

    events_ds = read_dataset(args.events, "events")
    measured = events_table(events_ds)
    fit = read_fit(args.fit)
    simulated = read_dataset(args.simulated, "simulated recording")
    steps = read_dataset(args.steps, "solver steps") if args.steps else None
    waves = read_table(args.waves) if args.waves is not None else None
    simulated_waves = (read_table(args.simulated_waves) if args.simulated_waves is not None
                       else None)
    scatter = read_table(args.scatter) if args.scatter is not None else None
    check_same_test([(args.events, events_ds.attrs), (args.fit, fit),
                     (args.simulated, simulated.attrs)]
                    + [(path, item.attrs) for path, item in [
                        (args.steps, steps), (args.waves, waves), (args.scatter, scatter),
                        (args.simulated_waves, simulated_waves)]
                       if item is not None])
    detection = _detection_settings(args)
    _check_detection(fit, detection, args.fit)
    table = compare_test(measured, simulated, steps, waves,
                         min_drop=float(events_ds.attrs.get("min_drop", float("nan")))
                         if "min_drop" in events_ds.attrs else None,
                         scatter=scatter,
                         detection=detection, simulated_waves=simulated_waves)
    summary: dict[str, Any] = {"test_id": fit["test_id"],
                               "recording_sha256": fit["recording_sha256"],
                               "law": fit["chosen"], "parameters": fit["parameters"],
                               "verdicts": verdict_counts(table)}
    if scatter is not None:
        summary["scatter_left_out"] = left_out_neighbours(
            chosen_law(fit), float(fit["load_calibration"]), scatter)
    if args.map is not None:
        setup = fit["setup"]
        ratio = setup["height_mm"]["value"] / setup["length_mm"]["value"]
        behaviour_map = read_dataset(args.map, "behaviour map")
        summary["map"] = place_on_map(behaviour_map, ratio, fit["parameters"]["fs"])
    write_table(table, args.output, fit)
    if args.json is not None:
        with atomic_output(args.json) as temporary:
            temporary.write_text(json.dumps(summary, indent=2), encoding="utf-8")
    if args.simulated_events is not None:
        write_table(table.attrs["simulated_events"], args.simulated_events, fit)
    counts = ", ".join(f"{n} {verdict}" for verdict, n in summary["verdicts"].items())
    print(f"{args.events} vs {args.simulated} -> {args.output}: {counts}")


def _fits(args: argparse.Namespace) -> None:
    from slipwave.fit import read_fit
    from slipwave.fits import fits_table
    from slipwave.io import atomic_output, write_table

    table = fits_table([read_fit(path) for path in args.fits])
    write_table(table, args.output)
    if args.plot is not None:
        from slipwave.plot import plot_fits
        with atomic_output(args.plot) as temporary:
            plot_fits(table).savefig(temporary, format=args.plot.suffix.lstrip(".") or "png",
                                     dpi=150, bbox_inches="tight")
    print(f"{len(table)} tests -> {args.output}")


def _compile(args: argparse.Namespace) -> None:
    import json

    from slipwave.compilation import compile_kernels
    from slipwave.io import atomic_output

    report = compile_kernels(args.processes)
    with atomic_output(args.output) as temporary:
        temporary.write_text(json.dumps(report, indent=2) + "\n")
    for name, part in (("solver", report), ("detection", report["detection"]),
                       ("quasi-dynamic contact", report["quasi_dynamic"])):
        kernels = part["kernels"].values()
        print(f"{name}: {len(kernels)} kernels, "
              f"{sum(kernel['compiled'] for kernel in kernels)} compiled now and "
              f"{sum(kernel['loaded'] for kernel in kernels)} loaded from the disk cache, in "
              f"{part['seconds']:.1f} s")
    print(f"-> {args.output}")


def _summary(args: argparse.Namespace) -> None:
    import pandas as pd

    from slipwave.events import summary_row
    from slipwave.io import read_dataset, write_table

    rows: list[dict[str, object]] = []
    for path in args.events:
        dataset = read_dataset(path, "events")
        test_id = str(dataset.attrs["test_id"])
        if any(row["test_id"] == test_id for row in rows):
            raise SlipwaveError(f"{path}: test {test_id!r} again: each test's events once")
        rows.append(summary_row(test_id, dataset))
    write_table(pd.DataFrame(rows), args.output)
    print(f"{len(rows)} tests -> {args.output}")


def _kymograph(args: argparse.Namespace) -> None:
    from slipwave.io import write_dataset
    from slipwave.video import Geometry, find_geometry, kymograph, open_frames

    source = open_frames(args.frames, fps=args.fps, keep_partial=args.keep_partial)
    if args.geometry:
        row, left, right = args.geometry
        geometry = Geometry(int(row), left, right, args.length)
    else:
        geometry = find_geometry(source, args.length)
    kymo = kymograph(source, geometry, band_mm=_band(args.band))
    kymo.attrs["source"] = str(args.frames)
    kymo.attrs["warnings"] = "\n".join(source.warnings)
    if args.test_id is not None:
        kymo.attrs["test_id"] = args.test_id
    write_dataset(kymo, args.output)
    _print_warnings(args.frames, kymo.attrs)
    print(f"{args.frames} -> {args.output}: {kymo.sizes['time']} frames, contact at columns "
          f"{geometry.left:g}-{geometry.right:g}, interface row {geometry.interface_row}")


def _waves(args: argparse.Namespace) -> None:
    from slipwave.events import events_table
    from slipwave.identity import check_same_test
    from slipwave.io import atomic_output, read_dataset, write_table
    from slipwave.video import align_clocks, fuse, on_card_clock, track_waves

    kymo = read_dataset(args.kymograph, "kymograph")
    recording = read_dataset(args.recording, "recording")
    events_ds = read_dataset(args.events, "events")
    check_same_test([(args.recording, recording.attrs), (args.events, events_ds.attrs)])
    if kymo.attrs.get("test_id"):  # a video names its test, not a recording
        check_same_test([(args.recording, recording.attrs), (args.kymograph, kymo.attrs)],
                        keys=("test_id",))
    events = events_table(events_ds)
    waves = track_waves(kymo)
    clock = align_clocks(waves, kymo, recording, events)
    waves = on_card_clock(waves, clock)
    write_table(waves, args.output, recording.attrs)
    write_table(fuse(events, waves, clock), args.fused, recording.attrs)
    with atomic_output(args.clock) as temporary:
        temporary.write_text(clock.to_json())
    print(f"{args.kymograph} -> {args.output}: {len(waves)} waves; camera clock: "
          f"card = {clock.offset:.4f} s + {clock.rate:.6f} x camera ({clock.method}, residual "
          f"{clock.residual * 1000:.1f} ms)")


def _report(args: argparse.Namespace) -> None:
    from slipwave.compare import read_comparison
    from slipwave.fit import read_fit
    from slipwave.fit_waves import read_waves_fit
    from slipwave.identity import check_same_test
    from slipwave.io import read_dataset, read_table
    from slipwave.report import pairing_summary, video_summary, write_test_page
    from slipwave.video import read_clock

    recording = read_dataset(args.recording, "recording")
    events = None if args.events is None else read_dataset(args.events, "events")
    fit = None if args.fit is None else read_fit(args.fit)
    simulated = (None if args.simulated is None
                 else read_dataset(args.simulated, "simulated recording"))
    contact = None if args.contact is None else read_dataset(args.contact, "contact history")
    quasi_dynamic = (None if args.quasi_dynamic is None
                     else read_dataset(args.quasi_dynamic, "quasi-dynamic run"))
    simulated_film = (None if args.simulated_film is None
                      else read_dataset(args.simulated_film, "kymograph"))
    given = [value is not None for value in (quasi_dynamic, args.simulated_waves,
                                             args.simulated_fronts, simulated_film)]
    if any(given) and not all(given):
        raise SlipwaveError("--quasi-dynamic, --simulated-waves, --simulated-fronts and "
                            "--simulated-film go together")
    if args.waves_fit is not None and quasi_dynamic is None:
        raise SlipwaveError("--waves-fit needs the run under its law (--quasi-dynamic)")
    waves_fit = None if args.waves_fit is None else read_waves_fit(args.waves_fit)
    compared = {} if args.comparison_json is None else read_comparison(args.comparison_json)
    tables = {option: None if path is None else read_table(path) for option, path in [
        ("waves", args.waves), ("fused", args.fused), ("comparison", args.comparison),
        ("simulated_events", args.simulated_events),
        ("simulated_waves", args.simulated_waves),
        ("simulated_fronts", args.simulated_fronts)]}
    check_same_test([(args.recording, recording.attrs)] + [
        (path, content) for path, content in [
            (args.events, None if events is None else events.attrs), (args.fit, fit),
            (args.simulated, None if simulated is None else simulated.attrs),
            (args.contact, None if contact is None else contact.attrs),
            (args.quasi_dynamic, None if quasi_dynamic is None else quasi_dynamic.attrs),
            (args.simulated_film, None if simulated_film is None else simulated_film.attrs),
            (args.comparison_json, compared or None), (args.waves_fit, waves_fit),
            *[(getattr(args, option), None if table is None else table.attrs)
              for option, table in tables.items()]] if content is not None])
    video = None
    kymo = clock = None
    if args.kymograph is not None:
        if tables["waves"] is None or args.clock is None:
            raise SlipwaveError("--kymograph needs --waves and --clock")
        kymo = read_dataset(args.kymograph, "kymograph")
        clock = read_clock(args.clock)
        video = video_summary(kymo, tables["waves"], clock, args.frames, events,
                              tables["fused"], quasi_dynamic, tables["simulated_waves"],
                              tables["simulated_fronts"], simulated_film, waves_fit)
    pairing = None
    if fit is not None or simulated is not None:
        behaviour_map = None if args.map is None else read_dataset(args.map, "behaviour map")
        pairing = pairing_summary(
            recording, events, fit=fit, comparison=tables["comparison"], simulated=simulated,
            simulated_events=tables["simulated_events"], contact=contact,
            placement=compared.get("map"), behaviour_map=behaviour_map, kymo=kymo,
            clock=clock, scatter_left_out=compared.get("scatter_left_out"))
    write_test_page(recording, args.output, events, video, pairing, pdf=args.pdf,
                    workers=args.threads)
    print(f"{args.recording} -> {args.output}" + (f", {args.pdf}" if args.pdf else ""))


def _campaign_report(args: argparse.Namespace) -> None:
    from slipwave.campaign_report import campaign_summary, write_campaign_report
    from slipwave.compare import read_comparison
    from slipwave.identity import test_id_problem
    from slipwave.io import read_dataset, read_table

    comparisons = {}
    for path in args.comparisons:
        content = read_comparison(path)
        comparisons[str(content["test_id"])] = content
    behaviour_map = None if args.map is None else read_dataset(args.map, "behaviour map")
    summary = read_table(args.summary, ["test_id"])
    for line, test_id in enumerate(summary["test_id"].astype(str), start=2):
        problem = test_id_problem(test_id)
        if problem is not None:  # ids name the pages the report links to
            raise SlipwaveError(f"{args.summary}, line {line}: {problem}")
    content = campaign_summary(summary,
                               None if args.fits is None else read_table(args.fits, ["test_id"]),
                               comparisons, behaviour_map)
    write_campaign_report(content, args.output, pdf=args.pdf, title=args.title)
    print(f"{len(content['tests'])} tests -> {args.output}" + (f", {args.pdf}" if args.pdf
                                                               else ""))


def _check_config(args: argparse.Namespace) -> None:
    from slipwave.campaign import check_campaign, check_config_files, read_campaign
    from slipwave.validation import load_schema

    # the workflow's own checks, run before Snakemake reads the files: Snakemake's
    # reader names no line when a file is not YAML
    config = check_config_files([args.workflow_config, *args.configs], load_schema("config"),
                                command_line=args.configs)
    if config.get("kind") == "spring_slider":
        from slipwave.slider_campaign import read_slider_campaign

        records = config.get("sliders", {}).get(
            "records", default.setting_schema("sliders", "records")["default"])
        table = read_slider_campaign(records)
        print(f"{', '.join(map(str, args.configs))}: valid; {len(table)} spring-slider "
              f"records in {records} ({(table['role'] == 'fit').sum()} to fit)")
        return
    campaign = read_campaign(config["tests"])
    check_campaign(config, campaign, load_schema("tests"))
    print(f"{', '.join(map(str, args.configs)) or args.workflow_config}: valid; "
          f"{len(campaign)} tests in {config['tests']}")


def _simulate(args: argparse.Namespace) -> None:
    from slipwave.io import write_dataset
    from slipwave.resources import require_memory
    from slipwave.solver import (
        Coulomb,
        LoadPath,
        Slab,
        describe_behaviour,
        simulate,
        simulation_memory,
    )

    if args.fit is not None:
        _simulate_test(args)
        return
    if args.fs is None:
        raise SlipwaveError("simulate needs --fs (or --fit, to simulate a test)")
    slab = Slab(length=args.length, height=args.height, width=args.width,
                youngs_modulus=args.youngs_modulus, poisson_ratio=args.poisson_ratio,
                elements=args.elements, holder=args.holder)
    path = LoadPath(normal_load=args.normal_load, tangential_step=args.tangential_step,
                    normal_control=args.normal_control, max_travel=args.max_travel,
                    travel_step=args.travel_step, machine_stiffness=args.machine_stiffness,
                    normal_friction=args.normal_friction == "on")
    require_memory(simulation_memory(slab, path), f"simulating a slab of {args.elements} elements "
                   f"and H = {args.height:g} mm", limit_gb=args.memory_limit)
    result = simulate(slab, Coulomb(fs=args.fs, fd=args.fd), path, cache=_solver_cache(args))
    behaviour = describe_behaviour(result)
    result.attrs["behaviour"] = behaviour.text
    result.attrs["behaviour_events"] = behaviour.to_json()
    write_dataset(result, args.output)
    if args.plot:
        from slipwave.plot import plot_zones

        plot_zones(result).savefig(args.plot, dpi=120)
    ratio = "not reached" if behaviour.ratio_at_gross is None else f"{behaviour.ratio_at_gross:.4f}"
    print(f"{args.output}: {result.sizes['step']} steps, T/N at gross sliding {ratio}, "
          f"behaviour: {behaviour.text}")


def _check_detection(fit: Mapping[str, Any], detection: DetectionSettings,
                     path: object) -> None:
    """Refuse a fit made with other detection settings than the command's."""
    from slipwave.events import DetectionSettings

    if "detection" in fit and DetectionSettings.from_dict(fit["detection"]) != detection:
        raise SlipwaveError(f"{path}: fitted with the detection settings {fit['detection']}, "
                            f"not these ({detection.to_dict()}): fit the test again")


def _simulate_test(args: argparse.Namespace) -> None:
    from slipwave.fit import chosen_law, read_fit
    from slipwave.identity import stamp
    from slipwave.io import write_dataset, write_table
    from slipwave.resources import require_memory
    from slipwave.setup import TestSetup
    from slipwave.simulate import replay_test, sequence_scatter

    fit = read_fit(args.fit)
    detection = _detection_settings(args)
    _check_detection(fit, detection, args.fit)
    setup = TestSetup.from_dict(fit["setup"])
    law, min_drop = chosen_law(fit), float(fit["measured"]["min_drop_n"])
    require_memory(setup.simulation_memory(int(fit["elements"]), args.sample_rate),
                   f"simulating test {setup.test_id!r} with {fit['elements']} elements at "
                   f"{args.sample_rate:g} Hz", limit_gb=args.memory_limit)
    cache = _solver_cache(args)
    replay = replay_test(setup, law, elements=int(fit["elements"]),
                         sample_rate=args.sample_rate, min_drop=min_drop,
                         kymograph=args.contact is not None, band_mm=_band(args.band),
                         detection=detection, cache=cache)
    stamp(replay.recording.attrs, "simulated recording", fit)
    write_dataset(replay.recording, args.output)
    if args.contact is not None:
        stamp(replay.contact.attrs, "contact history", fit)
        write_dataset(replay.contact, args.contact)
    if args.steps is not None:
        # the nodal displacements are the bulk of it, and the contact history has them
        steps = replay.simulation.drop_vars(["ux", "uy", "ux_before_wave", "uy_before_wave"])
        stamp(steps.attrs, "solver steps", fit)
        write_dataset(steps, args.steps)
    if args.scatter is not None:
        # the neighbours lie a load cell's calibration apart: the fit's own
        scatter = sequence_scatter(setup, law, elements=int(fit["elements"]),
                                   sample_rate=args.sample_rate, min_drop=min_drop,
                                   gross_edge_ratio=replay.recording.attrs["gross_edge_ratio"],
                                   step=float(fit["load_calibration"]), detection=detection,
                                   cache=cache)
        write_table(scatter, args.scatter, fit)
        if scatter.attrs["left_out"]:
            print(f"the law's scatter leaves out the neighbours the solver does not follow: "
                  f"{scatter.attrs['left_out']}")
    print(f"{args.fit} -> {args.output}: {fit['chosen']} "
          f"{', '.join(f'{k} {v:.4g}' for k, v in fit['parameters'].items())}, "
          f"{replay.simulation.sizes['step']} steps, gross/partial edge threshold "
          f"{replay.recording.attrs['gross_edge_ratio']:.3g}")


def _video_frames(path: Path, fit: Mapping[str, Any]) -> tuple[float, tuple[float, float]]:
    """A test's video's frame rate and band above the interface, from its kymograph."""
    import numpy as np

    from slipwave.identity import check_same_test
    from slipwave.io import read_dataset

    video = read_dataset(path, "kymograph")
    if video.attrs.get("test_id"):
        check_same_test([("the fit", fit), (path, video.attrs)], keys=("test_id",))
    times = video["time"].values
    if times.size < 2:
        raise SlipwaveError(f"{path}: fewer than two frames, no frame rate")
    low, high = (float(value) for value in video.attrs["band_mm"])
    return 1.0 / float(np.median(np.diff(times))), (low, high)


def _simulate_waves(args: argparse.Namespace) -> None:
    from slipwave.fit import read_fit
    from slipwave.fit_waves import read_waves_fit
    from slipwave.identity import check_same_test, stamp
    from slipwave.io import write_dataset, write_table
    from slipwave.setup import TestSetup
    from slipwave.simulate_waves import rate_state_law, simulate_waves

    fit = read_fit(args.fit)
    setup = TestSetup.from_dict(fit["setup"])
    frame_rate, band = _video_frames(args.kymograph, fit)
    given = {name: getattr(args, name) for name in default.WAVES_LAW}
    if args.law_fit is not None:
        if any(value is not None for value in given.values()):
            raise SlipwaveError("--law-fit gives the law: give it or the law's own options, "
                                "not both")
        fitted = read_waves_fit(args.law_fit)
        check_same_test([(args.fit, fit), (args.law_fit, fitted)])
        given = fitted["law"]
    law = rate_state_law({name: default.WAVES_LAW[name] if value is None else value
                          for name, value in given.items()})
    result = simulate_waves(setup, law, elements=args.elements, field_rate=args.field_rate,
                            sample_rate=args.sample_rate, frame_rate=frame_rate,
                            band_mm=band)
    stamp(result.run.attrs, "quasi-dynamic run", fit)
    stamp(result.film.attrs, "kymograph", fit)
    write_dataset(result.run, args.output)
    write_dataset(result.film, args.film)
    write_table(result.waves, args.waves, fit)
    write_table(result.fronts, args.fronts, fit)
    speeds = result.waves["speed"].dropna()
    fronts = result.fronts["speed"].dropna()
    print(f"{args.fit} -> {args.output}: {setup.test_id} under the "
          f"{result.run.attrs['law_text']}, {args.elements} elements, filmed at "
          f"{frame_rate:.4g} frames/s: {len(result.waves)} waves on the film, median speed "
          f"{f'{speeds.median():.0f} mm/s' if len(speeds) else 'none'}; {len(result.fronts)} "
          f"slip-rate fronts, median {f'{fronts.median():.0f} mm/s' if len(fronts) else 'none'}; "
          f"{result.run.attrs['steps']} steps")


def _fit_waves(args: argparse.Namespace) -> None:
    import json

    from slipwave.fit import read_fit
    from slipwave.fit_waves import WavesFitSettings, filmed_test, fit_filmed_test, fit_record
    from slipwave.identity import check_same_test, stamp
    from slipwave.io import atomic_output, read_dataset, read_table
    from slipwave.setup import TestSetup

    fit = read_fit(args.fit)
    recording = read_dataset(args.recording, "recording")
    waves = read_table(args.waves, ["t_start_card", "kind", "speed"])
    check_same_test([(args.fit, fit), (args.recording, recording.attrs),
                     (args.waves, waves.attrs)])
    detection = _detection_settings(args)
    _check_detection(fit, detection, args.fit)
    frame_rate, band = _video_frames(args.kymograph, fit)
    test = filmed_test(TestSetup.from_dict(fit["setup"]), recording, waves,
                       frame_rate=frame_rate, band_mm=band, detection=detection)
    print(f"{fit['test_id']}: {test.windows} windows of {test.window:.3g} s from "
          f"{test.settle:.3g} s after the loading, {test.waves} waves ({test.followed} "
          f"followed)", flush=True)
    settings = WavesFitSettings(**{name: getattr(args, name)
                                   for name in default.FIT_WAVES_TUNABLES},
                                processes=args.processes)
    posterior = fit_filmed_test(test, settings,  # each round to the log as it ends
                                progress=lambda line: print(line, flush=True))
    record = fit_record(test, posterior, settings)
    stamp(record, None, fit)
    with atomic_output(args.output) as temporary:
        temporary.write_text(json.dumps(record, indent=2), encoding="utf-8")
    values = ", ".join(f"{name} {p['value']:.4g} [{p['low']:.4g}, {p['high']:.4g}]"
                       for name, p in record["parameters"].items())
    print(f"{args.fit} -> {args.output}: {values}; {record['guesses']} guesses")


def _map_row(args: argparse.Namespace) -> None:
    import xarray as xr
    from tqdm import tqdm

    from slipwave.io import write_dataset
    from slipwave.map import friction_grid, map_row, shard
    from slipwave.resources import require_memory
    from slipwave.solver import LoadPath, Slab, simulation_memory

    frictions = shard(friction_grid(*args.frictions), args.shard, args.shard_size)
    path = LoadPath(normal_load=args.normal_load, tangential_step=args.tangential_step,
                    normal_control=args.normal_control,
                    normal_friction=args.normal_friction == "on")
    tallest = max(args.height_ratio)
    slab = Slab(height=tallest * default.CONTACT_LENGTH_MM, elements=args.elements)
    require_memory(simulation_memory(slab, path), f"the map's row at H/L {tallest:g} "
                   f"({args.elements} elements)", limit_gb=args.memory_limit)
    cache = _solver_cache(args)
    rows = []
    for ratio in args.height_ratio:
        with tqdm(total=frictions.size, desc=f"H/L {ratio:g}", unit="case",
                  mininterval=2.0, file=sys.stderr) as bar:
            row = map_row(ratio, frictions, elements=args.elements, path=path,
                          min_size=args.min_zone, cache=cache,
                          progress=lambda done, total: bar.update(1))
        seconds = row["seconds"].values
        # wall times go to the log, not the map: the map is the same on any machine
        condensation = row.attrs.pop("condensation_s")
        print(f"H/L {ratio:g}: {frictions.size} cases in {seconds.sum():.1f} s "
              f"(mean {1000 * seconds.mean():.1f} ms, condensation {condensation} s), "
              f"largest residual {float(row['max_residual'].max()):.2g}")
        rows.append(row.drop_vars("seconds"))
    joined = xr.concat(rows, dim="height_ratio", combine_attrs="drop_conflicts")
    write_dataset(joined, args.output)
    print(f"{len(rows)} rows of {frictions.size} cases -> {args.output}")


def _map_assemble(args: argparse.Namespace) -> None:
    from slipwave.io import atomic_output, read_dataset, write_dataset, write_table
    from slipwave.map import assemble_map, behaviour_legend, map_table, mesh_band

    whole = assemble_map([read_dataset(path, "map row") for path in args.rows])
    if args.band_rows:
        coarser = assemble_map([read_dataset(path, "map row") for path in args.band_rows])
        whole["mesh_band"] = mesh_band(whole, coarser, args.band_steps)
        whole.attrs.update(band_elements=coarser.attrs["contact_elements"],
                           band_steps=args.band_steps)
        moved = int((whole["sequence"].values != coarser["sequence"].values).sum())
        print(f"{moved} successions differ between {coarser.attrs['contact_elements']} and "
              f"{whole.attrs['contact_elements']} elements; the band (+-{args.band_steps} f "
              f"steps) covers {float(whole['mesh_band'].mean()):.1%} of the map")
    write_dataset(whole, args.output)
    write_table(map_table(whole), args.csv)
    with atomic_output(args.legend) as temporary:
        temporary.write_text(behaviour_legend(whole) + "\n")
    failed = int((whole["end"].values != "gross sliding").sum())
    print(f"{whole['behaviour'].size} cases, {whole.sizes['behaviour_id']} behaviours, "
          f"{failed} without gross sliding, largest residual "
          f"{float(whole['max_residual'].max()):.2g} -> {args.output}")


def _map_figures(args: argparse.Namespace) -> None:
    from slipwave.io import atomic_output, read_dataset, read_table
    from slipwave.map import place_tests, representative_cases, simulate_case
    from slipwave.plot import plot_map, plot_zone_histories

    whole = read_dataset(args.map, "behaviour map")
    tests = None
    if args.summary is not None:
        ratios: dict[str, float | str] = {}
        for test_id, text in args.test_ratio:
            try:
                ratios[test_id] = float(text)
            except ValueError as err:
                raise SlipwaveError(f"--test-ratio {test_id}={text}: H/L must be a number") from err
        tests = place_tests(read_table(args.summary, ["test_id"]), ratios)
    with atomic_output(args.figure) as temporary:
        plot_map(whole, tests).savefig(temporary, dpi=130, format="png")
    if args.zones is not None:
        cache = _solver_cache(args)
        cases = [(f"{name}: H/L {hl:g}, f {f:.2f}",
                  simulate_case(whole, float(hl), float(f), cache=cache))
                 for name, hl, f in representative_cases(whole)[["name", "height_ratio",
                                                                "friction"]].itertuples(
                                                                    index=False)]
        with atomic_output(args.zones) as temporary:
            plot_zone_histories(cases).savefig(temporary, dpi=130, format="png")
    placed = 0 if tests is None else len(tests)
    print(f"{args.map} -> {args.figure}" + (f", {args.zones}" if args.zones else "")
          + f" ({placed} tests placed)")


def _bench(args: argparse.Namespace) -> None:
    from slipwave.bench.generate import read_bench_config, write_campaign

    table = write_campaign(read_bench_config(args.config), args.output, seed=args.seed,
                           progress=not args.quiet, memory_limit_gb=args.memory_limit,
                           cache=_solver_cache(args))
    print(f"{args.config} -> {args.output} ({table.name})")


def _slider_ingest(args: argparse.Namespace) -> None:
    from slipwave.identity import stamp
    from slipwave.io import write_dataset
    from slipwave.io.slider_record import read_slider_record
    from slipwave.slider_campaign import GRAVITY

    record = read_slider_record(args.mat)
    stamp(record.attrs, "spring-slider record")
    mass = args.mass * 1e-3
    record.attrs.update({
        "record_id": args.record_id, "role": args.role, "stiffness_n_m": args.stiffness,
        "drive_speed_m_s": args.drive_speed * 1e-6, "mass_kg": mass,
        "normal_load_n": args.normal_load if args.normal_load is not None else mass * GRAVITY,
        "window_s": args.window})
    write_dataset(record, args.output)
    print(f"{args.mat} -> {args.output}: {record.sizes['time']} samples")


def _slider_fit(args: argparse.Namespace) -> None:
    import time as clock

    from slipwave.fit.slider import (
        SliderFitSettings,
        fit_records,
        posterior_dataset,
        posterior_json,
        record_of,
    )
    from slipwave.identity import stamp
    from slipwave.io import atomic_output, read_dataset, write_dataset

    started = clock.perf_counter()
    datasets = [read_dataset(path, "spring-slider record") for path in args.records]
    held_out = [f"{path} ({dataset.attrs['role']})"
                for path, dataset in zip(args.records, datasets, strict=True)
                if dataset.attrs["role"] != "fit"]
    if held_out:  # a held-out record is never read by the fit
        raise SlipwaveError(f"records whose role is not fit given to the fit: "
                            f"{', '.join(held_out)}")
    records = [record_of(dataset) for dataset in datasets]
    settings = SliderFitSettings(members=args.members, design=args.design,
                                 acquisitions=args.acquisitions, exploration=args.exploration,
                                 samples=args.samples, processes=args.processes, seed=args.seed,
                                 evolution=args.evolution, states=args.states,
                                 cutoff=args.cutoff)
    posterior = fit_records(records, settings, progress=print)
    seconds = clock.perf_counter() - started
    dataset = posterior_dataset(posterior, settings, seconds)
    stamp(dataset.attrs, "spring-slider posterior")
    write_dataset(dataset, args.posterior)
    with atomic_output(args.output) as temporary:
        temporary.write_text(posterior_json(posterior, settings, seconds), encoding="utf-8")
    for name, (middle, low, high) in posterior.interval().items():
        print(f"{name}: {middle:.4g} [{low:.4g}, {high:.4g}]")
    print(f"{len(records)} records fitted in {seconds:.0f} s -> {args.output}")


def _slider_predict(args: argparse.Namespace) -> None:
    import json

    from slipwave.fit.slider import posterior_of, predict_record, record_of
    from slipwave.io import atomic_output, read_dataset

    dataset = read_dataset(args.record, "spring-slider record")
    record = record_of(dataset)
    posterior = posterior_of(read_dataset(args.posterior, "spring-slider posterior"))
    prediction = predict_record(record, posterior, args.draws, args.members, args.seed)
    prediction["role"] = str(dataset.attrs["role"])
    prediction["fitted_on_it"] = record.name in posterior.records
    with atomic_output(args.output) as temporary:
        temporary.write_text(json.dumps(prediction, indent=2), encoding="utf-8")
    regime = prediction["regime"]
    print(f"{record.name}: regime predicted {regime['predicted']}, measured "
          f"{regime['measured']} -> {args.output}")


def _slider_report(args: argparse.Namespace) -> None:
    from slipwave.slider_report import write_slider_report

    write_slider_report(args.fit, args.predictions, args.output)
    print(f"-> {args.output}")


def _sawtooth(args: argparse.Namespace) -> None:
    from slipwave.bench.sawtooth import write_sawtooth_campaign

    for path in write_sawtooth_campaign(args.output, seed=args.seed):
        print(path)


def _detection_options() -> argparse.ArgumentParser:
    """The detection's settings, shared by every command that detects slips."""
    options = argparse.ArgumentParser(add_help=False)
    group = options.add_argument_group("detection (the campaign's 'detection' section)")
    group.add_argument("--threshold", type=_setting("detection", "threshold"),
                       default=default.THRESHOLD,
                       help="default thresholds in noise standard deviations (%(default)s)")
    group.add_argument("--max-spike", type=_setting("detection", "max_spike"),
                       default=default.MAX_SPIKE,
                       help="longest spike ignored, samples (%(default)s)")
    group.add_argument("--max-duration", type=_optional_float, default=default.MAX_DURATION_S,
                       help="longest drop looked for, s ('none': a tenth of the recording)")
    group.add_argument("--min-fall-rate", type=_setting("detection", "min_fall_rate"),
                       default=default.MIN_FALL_RATE,
                       help="how many times faster than the drive loads T a drop must fall "
                       "(%(default)s)")
    group.add_argument("--edge-convention", choices=["auto", "x_axis", "outward"],
                       default=default.EDGE_CONVENTION,
                       help="how the edge sensors read: both along +x, each its edge's outward "
                       "displacement, or found from the data (%(default)s)")
    return options


def _cache_options() -> argparse.ArgumentParser:
    """Where a command keeps the slabs' condensations for the next one."""
    options = argparse.ArgumentParser(add_help=False)
    options.add_argument("--cache-dir", type=Path,
                         default=os.environ.get("SLIPWAVE_CACHE_DIR") or None,
                         help="folder where the slabs' condensed matrices are kept across "
                         "runs (default: $SLIPWAVE_CACHE_DIR; unset: none kept)")
    return options


def _memory_options() -> argparse.ArgumentParser:
    """The cap on what a command may plan to use, checked before it starts."""
    options = argparse.ArgumentParser(add_help=False)
    options.add_argument("--memory-limit", type=_positive_float, default=None, metavar="GB",
                         help="refuse a run whose estimated memory exceeds this (default: "
                         "$SLIPWAVE_MEMORY_LIMIT_GB, else the memory available)")
    return options


def _load_path_arguments(parser: argparse.ArgumentParser, *, normal_control: str,
                         normal_friction: str) -> None:
    """The options of a :class:`~slipwave.solver.LoadPath` that `simulate` and `map row` share."""
    parser.add_argument("--normal-load", type=float, default=default.NORMAL_LOAD_N,
                        help="N, newtons (%(default)s)")
    parser.add_argument("--tangential-step", type=float, default=default.TANGENTIAL_STEP_N,
                        help="T step, newtons (%(default)s)")
    parser.add_argument("--normal-control", choices=["force", "displacement"],
                        default=normal_control, help="held after the normal loading: N "
                        "(force) or the flat's normal position (%(default)s)")
    parser.add_argument("--normal-friction", choices=["on", "off"], default=normal_friction,
                        help="friction during the normal loading (%(default)s)")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``slipwave`` (exposed for documentation and tests).

    Returns
    -------
    argparse.ArgumentParser
        With one subcommand per stage.

    """
    parser = argparse.ArgumentParser(
        prog="slipwave", description="Friction-bench recordings to answers."
    )
    parser.add_argument("--version", action="version", version=f"slipwave {__version__}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    detection, cache, memory = _detection_options(), _cache_options(), _memory_options()

    ingest = commands.add_parser(
        "ingest", help="read an acquisition CSV, write it as CF netCDF",
        description="Read an acquisition CSV (any supported dialect) and write it as "
        "compressed CF netCDF in N, mm and s.",
    )
    ingest.add_argument("raw", type=Path, help="acquisition CSV (opened read-only)")
    ingest.add_argument("-o", "--output", type=Path, required=True, help="netCDF to write")
    ingest.add_argument("--test-id", default=None, help="the test's id, which every product "
                        "made from the recording carries (default: the header's test_id, "
                        "else the file's name)")
    ingest.add_argument(
        "--columns", type=_column_pair, nargs="*", default=[], metavar="NAME=CHANNEL",
        help="map header names (without their unit) to time, index, T, N, DG, DD, DT or "
        "ignore",
    )
    ingest.set_defaults(run=_ingest)

    report = commands.add_parser("report", help="write the HTML page of one test")
    report.add_argument("recording", type=_input, help="recording netCDF from 'slipwave ingest'")
    report.add_argument("-o", "--output", type=Path, required=True, help="HTML page to write")
    report.add_argument("--events", type=_input, default=None,
                        help="events netCDF from 'slipwave detect --netcdf' (phases, slips)")
    report.add_argument("--kymograph", type=_input, default=None,
                        help="kymograph netCDF from 'slipwave kymograph'")
    report.add_argument("--waves", type=_input, default=None, help="waves CSV of 'slipwave waves'")
    report.add_argument("--clock", type=_input, default=None, help="clock JSON of 'slipwave waves'")
    report.add_argument("--fused", type=_input, default=None,
                        help="events with their waves, CSV of 'slipwave waves --fused'")
    report.add_argument("--frames", type=_input, default=None,
                        help="the video (or image folder) for frames around the first gross slip")
    report.add_argument("--fit", type=_input, default=None, help="fit.json of 'slipwave fit'")
    report.add_argument("--comparison", type=_input, default=None,
                        help="comparison CSV of 'slipwave compare'")
    report.add_argument("--comparison-json", type=_input, default=None,
                        help="comparison JSON of 'slipwave compare --json' (place on the map)")
    report.add_argument("--simulated", type=_input, default=None,
                        help="simulated recording of 'slipwave simulate --fit'")
    report.add_argument("--simulated-events", type=_input, default=None,
                        help="simulated events CSV of 'slipwave compare'")
    report.add_argument("--contact", type=_input, default=None,
                        help="simulated contact history of 'slipwave simulate --contact'")
    report.add_argument("--map", type=_input, default=None, help="behaviour map netCDF")
    report.add_argument("--quasi-dynamic", type=_input, default=None,
                        help="with --kymograph: the test run quasi-dynamically ('slipwave "
                        "simulate-waves -o'), its fronts shown beside the video's")
    report.add_argument("--simulated-waves", type=_input, default=None,
                        help="its film's waves ('slipwave simulate-waves --waves')")
    report.add_argument("--simulated-fronts", type=_input, default=None,
                        help="its slip-rate fronts ('slipwave simulate-waves --fronts')")
    report.add_argument("--simulated-film", type=_input, default=None,
                        help="its film's kymograph ('slipwave simulate-waves --film')")
    report.add_argument("--waves-fit", type=_input, default=None,
                        help="the law fitted on the test's cycle and waves ('slipwave "
                        "fit-waves -o'), the one its quasi-dynamic run ran under")
    report.add_argument("--pdf", type=Path, default=None, help="also print the page to PDF")
    report.add_argument("--threads", type=_positive_int, default=1,
                        help="processes to draw the figures on (default 1)")
    report.set_defaults(run=_report)

    campaign_report = commands.add_parser(
        "campaign-report", help="write the campaign report (HTML, PDF) over every test")
    campaign_report.add_argument("--summary", type=_input, required=True,
                                 help="summary CSV of 'slipwave summary'")
    campaign_report.add_argument("--fits", type=_input, default=None,
                                 help="fits CSV of 'slipwave fits'")
    campaign_report.add_argument("--comparisons", type=_input, nargs="*", default=[],
                                 help="comparison JSON files of 'slipwave compare --json'")
    campaign_report.add_argument("--map", type=_input, default=None, help="behaviour map netCDF")
    campaign_report.add_argument("--title", default="Campaign", help="the report's title")
    campaign_report.add_argument("-o", "--output", type=Path, required=True, help="HTML")
    campaign_report.add_argument("--pdf", type=Path, default=None, help="also write a PDF")
    campaign_report.set_defaults(run=_campaign_report)

    check_config = commands.add_parser(
        "check-config", help="check a campaign's config files and table as the workflow does",
        description="Check config files (and the campaign table they name) as 'snakemake "
        "--configfile' would, naming the file and line of each problem; Snakemake's own "
        "reader stops at a file that is not YAML without naming the line.")
    check_config.add_argument("configs", type=_input, nargs="*",
                              help="the --configfile files of the run")
    check_config.add_argument("--workflow-config", type=_input,
                              default=Path("config/config.yaml"),
                              help="the workflow's own config (%(default)s)")
    check_config.set_defaults(run=_check_config)

    sim = commands.add_parser(
        "simulate", parents=[detection, cache, memory],
        help="simulate a bench test with the frictional contact solver",
        description="Press the flat on the slab, then move it until gross sliding (or up to "
        "--max-travel), and write the zone evolution as netCDF.",
    )
    sim.add_argument("--height", type=float, default=default.SLAB_HEIGHT_MM,
                     help="slab height H, mm (%(default)s)")
    sim.add_argument("--length", type=float, default=default.CONTACT_LENGTH_MM,
                     help="contact length L, mm (%(default)s)")
    sim.add_argument("--width", type=float, default=default.SLAB_WIDTH_MM,
                     help="slab width w, mm (%(default)s)")
    sim.add_argument("--youngs-modulus", type=float, default=default.YOUNGS_MODULUS_MPA,
                     help="E, MPa (%(default)s)")
    sim.add_argument("--poisson-ratio", type=float, default=default.POISSON_RATIO,
                     help="nu (%(default)s)")
    sim.add_argument("--elements", type=_setting("map", "elements"), default=default.SLAB_ELEMENTS,
                     help="elements along the contact (%(default)s)")
    sim.add_argument("--holder", choices=["clamped", "free"], default="clamped")
    sim.add_argument("--fs", type=float, default=None,
                     help="static friction coefficient (required without --fit)")
    sim.add_argument("--fit", type=_input, default=None,
                     help="simulate a test: its fit.json from 'slipwave fit' (its setup, its "
                     "chosen law and mesh); -o then writes the simulated recording")
    sim.add_argument("--contact", type=Path, default=None,
                     help="with --fit: also write the zone history and simulated kymograph")
    sim.add_argument("--steps", type=Path, default=None,
                     help="with --fit: also write the solver's steps")
    sim.add_argument("--sample-rate", type=_positive_float, default=default.SAMPLE_RATE_HZ,
                     help="with --fit: sampling rate of the simulated recording, Hz")
    sim.add_argument("--band", type=float, nargs=2, default=list(default.BAND_MM),
                     metavar=("LOW", "HIGH"), help="with --fit: the simulated kymograph's band "
                     "above the interface, mm (the video's; %(default)s)")
    sim.add_argument("--scatter", type=Path, default=None,
                     help="with --fit: also simulate the law at coefficients a load cell's "
                     "calibration apart and write their compared features (CSV), the "
                     "simulation's own scatter for 'slipwave compare --scatter'")
    sim.add_argument("--fd", type=float, default=None, help="dynamic coefficient (fs)")
    _load_path_arguments(sim, normal_control=default.NORMAL_CONTROL,
                         normal_friction="on" if default.NORMAL_FRICTION else "off")
    sim.add_argument("--max-travel", type=float, default=None,
                     help="go on past gross sliding up to this flat travel, mm")
    sim.add_argument("--travel-step", type=float, default=None,
                     help="flat (or actuator) travel per step past gross sliding, mm")
    sim.add_argument("--machine-stiffness", type=float, default=None,
                     help="drive the flat through a spring of this stiffness (N/mm) from an "
                     "actuator, up to --max-travel in --travel-step steps")
    sim.add_argument("-o", "--output", type=Path, required=True, help="netCDF to write")
    sim.add_argument("--plot", type=Path, default=None, help="also draw the zones (PNG, SVG)")
    sim.set_defaults(run=_simulate)

    waves_sim = commands.add_parser(
        "simulate-waves",
        help="simulate a filmed test quasi-dynamically: its waves with a speed",
        description="Run the test's slab, normal load and drive through the quasi-dynamic "
        "contact under a rate-and-state law (aging), film it at the video's frame rate, "
        "and write the run and its film (netCDF), the film's waves and the run's slip-rate "
        "fronts in the video's columns (CSV), on the test's clock.")
    waves_sim.add_argument("--fit", type=_input, required=True,
                           help="the test's fit.json (its setup and identity)")
    for name, unit in (("a", ""), ("b", ""), ("dc_um", ", um"), ("mu0", ""),
                       ("v0_um_s", ", um/s")):
        waves_sim.add_argument(f"--{name.replace('_', '-')}",
                               type=_setting("simulate_waves", name), default=None,
                               help=f"the law's {name}{unit} ({default.WAVES_LAW[name]})")
    waves_sim.add_argument("--law-fit", type=_input, default=None,
                           help="the law fitted on the test ('slipwave fit-waves -o'): its "
                           "posterior's medians, in place of the law's options")
    waves_sim.add_argument("--elements", type=_setting("simulate_waves", "elements"),
                           default=default.WAVES_ELEMENTS,
                           help="elements along the contact (%(default)s)")
    waves_sim.add_argument("--field-rate", type=_setting("simulate_waves", "field_rate_hz"),
                           default=default.WAVES_FIELD_RATE_HZ,
                           help="records of the nodes' fields per second (%(default)s)")
    waves_sim.add_argument("--sample-rate", type=_positive_float,
                           default=default.SAMPLE_RATE_HZ,
                           help="records of the loads and sensors per second (%(default)s)")
    waves_sim.add_argument("--kymograph", type=_input, required=True,
                           help="the test's video's kymograph (its frame rate and band)")
    waves_sim.add_argument("-o", "--output", type=Path, required=True,
                           help="netCDF of the run")
    waves_sim.add_argument("--film", type=Path, required=True,
                           help="netCDF of the run's film's kymograph")
    waves_sim.add_argument("--waves", type=Path, required=True,
                           help="CSV of the film's waves (the video's columns)")
    waves_sim.add_argument("--fronts", type=Path, required=True,
                           help="CSV of the run's slip-rate fronts (the video's columns)")
    waves_sim.set_defaults(run=_simulate_waves)

    waves_fit = commands.add_parser(
        "fit-waves", parents=[detection],
        help="fit a filmed test's rate-and-state law on its cycle and its waves",
        description="Infer a, b - a, D_c and mu0 of the aging law (v0 1 um/s) from the "
        "test's slips in windows of three recurrences (T/|N| before them, their drop, their "
        "rate) and its video's followed waves' median speed, by a synthetic likelihood read "
        "from an emulator of quasi-dynamic runs of its slab, filmed as the bench films; write "
        "the medians and 95 % intervals, and the law the simulate-waves stage runs "
        "(slipwave.fit_waves).")
    waves_fit.add_argument("--fit", type=_input, required=True,
                           help="the test's fit.json (its setup, identity and detection)")
    waves_fit.add_argument("--recording", type=_input, required=True,
                           help="the test's recording ('slipwave ingest')")
    waves_fit.add_argument("--waves", type=_input, required=True,
                           help="its video's waves ('slipwave waves')")
    waves_fit.add_argument("--kymograph", type=_input, required=True,
                           help="its video's kymograph (its frame rate and band)")
    for key in default.FIT_WAVES_TUNABLES:
        waves_fit.add_argument(
            f"--{key.replace('_', '-')}", type=_setting("fit_waves", key),
            default=default.FIT_WAVES_DEFAULTS[key],
            help=default.setting_schema("fit_waves", key)["description"].replace("%", "%%")
            + " (%(default)s)")
    waves_fit.add_argument("--processes", type=_positive_int, default=1,
                           help="worker processes for the guesses' runs (%(default)s)")
    waves_fit.add_argument("-o", "--output", type=Path, required=True,
                           help="fit_waves.json to write")
    waves_fit.set_defaults(run=_fit_waves)

    mapping = commands.add_parser(
        "map", help="the behaviour map over f x H/L (the paper's figure 2)",
        description="'map row' runs every friction coefficient at one H/L (or several); "
        "'map assemble' joins the rows and numbers the behaviours; 'map figures' draws "
        "the map.",
    )
    steps = mapping.add_subparsers(dest="map_command", required=True, metavar="STEP")
    row = steps.add_parser("row", parents=[cache, memory],
                           help="every f at one H/L, or at several in turn (one file)")
    row.add_argument("--height-ratio", type=_positive_float, nargs="+", required=True,
                     help="H/L, one or more: the rows are computed one after another in "
                     "this process and written to one file")
    row.add_argument("--frictions", type=_positive_float, nargs=3,
                     default=list(default.MAP_FRICTIONS),
                     metavar=("START", "STOP", "STEP"), help="friction coefficients "
                     "(%(default)s)")
    row.add_argument("--elements", type=_setting("map", "elements"), default=default.MAP_ELEMENTS,
                     help="elements along the contact (%(default)s)")
    row.add_argument("--shard", type=_non_negative_int, default=0,
                     help="which run of --shard-size coefficients of the row, from 0")
    row.add_argument("--shard-size", type=_setting("map", "shard_size"), default=0,
                     help="coefficients per shard; 0: the whole row (%(default)s)")
    _load_path_arguments(row, normal_control=default.MAP_NORMAL_CONTROL,
                         normal_friction="on" if default.MAP_NORMAL_FRICTION else "off")
    row.add_argument("--min-zone", type=_setting("map", "min_zone_mm"), default=default.MIN_ZONE_MM,
                     help="shortest zone that decides anything, mm (%(default)s)")
    row.add_argument("-o", "--output", type=Path, required=True, help="netCDF to write")
    row.set_defaults(run=_map_row)
    assemble = steps.add_parser("assemble", help="join rows and name the behaviours")
    assemble.add_argument("rows", type=_input, nargs="+", help="netCDF rows of 'slipwave map row'")
    assemble.add_argument("-o", "--output", type=Path, required=True, help="map netCDF")
    assemble.add_argument("--csv", type=Path, required=True, help="map table (CSV)")
    assemble.add_argument("--legend", type=Path, required=True,
                          help="the behaviours in words (Markdown)")
    assemble.add_argument("--band-rows", type=_input, nargs="+", default=None,
                          help="the same cases at a coarser mesh: the band where the map "
                          "still moves with the mesh is drawn from them")
    assemble.add_argument("--band-steps", type=_setting("map", "band_steps"),
                          default=default.MAP_BAND_STEPS,
                          help="f steps the band is widened by on each side (%(default)s)")
    assemble.set_defaults(run=_map_assemble)
    figures = steps.add_parser("figures", parents=[cache],
                               help="draw the map and one zone history per "
                               "behaviour")
    figures.add_argument("map", type=_input, help="map netCDF of 'slipwave map assemble'")
    figures.add_argument("--figure", type=Path, required=True, help="map figure (PNG)")
    figures.add_argument("--zones", type=Path, default=None,
                         help="zone histories of one case per behaviour (PNG)")
    figures.add_argument("--summary", type=_input, default=None,
                         help="campaign summary CSV: tests placed on the map")
    figures.add_argument("--test-ratio", type=_column_pair, nargs="*", default=[],
                         metavar="TEST=H/L", help="H/L of each test's slab")
    figures.set_defaults(run=_map_figures)

    bench = commands.add_parser(
        "bench", parents=[cache, memory],
        help="generate a virtual-bench campaign (CSVs, videos, truth)",
        description="Simulate each test of CONFIG (YAML: defaults and tests) on the virtual "
        "bench and write its acquisition CSV, video and ground truth.",
    )
    bench.add_argument("config", type=_input, help="campaign YAML")
    bench.add_argument("-o", "--output", type=Path, required=True, help="campaign folder")
    bench.add_argument("--seed", type=_non_negative_int,
                       default=0, help="noise seed of the first test (0)")
    bench.add_argument("--quiet", action="store_true", help="no progress bar")
    bench.set_defaults(run=_bench)

    detect = commands.add_parser(
        "detect", parents=[detection], help="detect partial and gross slips in a recording",
        description="Find the T drops of a recording, classify them by the DG/DD jumps and "
        "write the events (CSV, and netCDF with the phase of every sample and the T/|N| "
        "ratios at gross slips).",
    )
    detect.add_argument("recording", type=_input, help="recording netCDF from 'slipwave ingest'")
    detect.add_argument("-o", "--output", type=Path, required=True, help="events CSV to write")
    detect.add_argument("--netcdf", type=Path, default=None,
                        help="also write events, phases and ratios as netCDF")
    detect.add_argument("--min-drop", type=_positive_float, default=None,
                        help="smallest T drop, N (default: --threshold x T noise)")
    detect.add_argument("--min-jump", type=_positive_float, default=None,
                        help="smallest DG/DD jump, mm (default: --threshold x noise)")
    detect.add_argument("--gross-edge-ratio", type=_setting("detection", "gross_edge_ratio"),
                        default=default.GROSS_EDGE_RATIO,
                        help="DG jump / DD jump from which a drop is a gross slip (%(default)s)")
    detect.add_argument("--simulated", type=_input, default=None,
                        help="the test's simulated recording ('slipwave simulate --fit'): its "
                        "gross_edge_ratio, read off the simulated slips, replaces "
                        "--gross-edge-ratio")
    detect.set_defaults(run=_detect)

    fit = commands.add_parser(
        "fit", parents=[detection, cache, memory],
        help="fit friction laws to a test through the solver",
        description="Read the test's configuration from its recording and the campaign "
        "table's cells, then fit each friction law on the slip events (T/|N| at gross "
        "slips, their times, slip counts) by its synthetic likelihood, with 95 % "
        "posterior intervals, and choose the law of highest evidence whose posterior "
        "predictive reproduces every feature.")
    fit.add_argument("recording", type=_input, help="recording netCDF from 'slipwave ingest'")
    fit.add_argument("-o", "--output", type=Path, required=True, help="fit.json to write")
    fit.add_argument("--setting", type=_setting_pair, nargs="*", default=[],
                     metavar="COLUMN=VALUE", help="the campaign table's cells (length_mm, "
                     "height_mm, width_mm, youngs_modulus_mpa, poisson_ratio, normal_load_n, "
                     "speed_mm_s, machine_stiffness_n_mm, edge_reference)")
    fit.add_argument("--laws", nargs="+", default=list(default.FIT_LAWS),
                     choices=list(default.FIT_LAWS), help="laws to fit (%(default)s)")
    fit.add_argument("--elements", type=_setting("fit", "elements"), default=default.FIT_ELEMENTS,
                     help="elements along the contact (%(default)s)")
    for key in default.FIT_TUNABLES:
        fit.add_argument(f"--{key.replace('_', '-')}", type=_setting("fit", key),
                         default=default.FIT_DEFAULTS[key],
                         help=default.setting_schema("fit", key)["description"].replace(
                             "%", "%%") + " (%(default)s)")
    fit.add_argument("--load-calibration", type=_setting("fit", "load_calibration"),
                     default=default.LOAD_CALIBRATION,
                     help="relative calibration uncertainty of each load cell (%(default)s)")
    fit.add_argument("--mesh-check", choices=["on", "off"],
                     default="on" if default.FIT_MESH_CHECK else "off",
                     help="refit the chosen law at twice the mesh and record each parameter's "
                     "change (%(default)s)")
    fit.set_defaults(run=_fit)

    compare = commands.add_parser(
        "compare", parents=[detection],
        help="a test's measurement against its simulation, feature by feature")
    compare.add_argument("events", type=_input, help="events netCDF of 'slipwave detect'")
    compare.add_argument("--simulated", type=_input, required=True,
                         help="simulated recording of 'slipwave simulate --fit'")
    compare.add_argument("--scatter", type=_input, default=None,
                         help="neighbouring simulations' features ('slipwave simulate "
                         "--scatter'): the simulation's own scatter widens the tolerances")
    compare.add_argument("--steps", type=_input, default=None,
                         help="the solver's steps ('slipwave simulate --steps')")
    compare.add_argument("--fit", type=_input, required=True, help="fit.json")
    compare.add_argument("--waves", type=_input, default=None, help="waves CSV of the video")
    compare.add_argument("--simulated-waves", type=_input, default=None,
                         help="waves CSV of 'slipwave simulate-waves': with --waves, the "
                         "wave speed, first wave and share over the whole contact compared")
    compare.add_argument("--map", type=_input, default=None, help="behaviour map netCDF")
    compare.add_argument("-o", "--output", type=Path, required=True, help="comparison CSV")
    compare.add_argument("--json", type=Path, default=None,
                         help="also write the verdict counts and the place on the map")
    compare.add_argument("--simulated-events", type=Path, default=None,
                         help="also write the simulated recording's events (CSV)")
    compare.set_defaults(run=_compare)

    fits = commands.add_parser("fits", help="the campaign's fits in one table")
    fits.add_argument("fits", type=_input, nargs="+", help="fit.json files")
    fits.add_argument("-o", "--output", type=Path, required=True, help="CSV to write")
    fits.add_argument("--plot", type=Path, default=None,
                      help="also draw T/|N| and the fitted coefficients against H/L")
    fits.set_defaults(run=_fits)

    compiling = commands.add_parser(
        "compile", help="compile the solver and the detection once (numba's disk cache), "
        "before the jobs that need them", description="Compile every kernel of the solver "
        "and of the detection, or load it from the disk cache, and report which (JSON).")
    compiling.add_argument("-o", "--output", type=Path, required=True, help="JSON to write")
    compiling.add_argument("--processes", type=_positive_int, default=1,
                           help="processes to compile on; two (more gain nothing): the "
                           "solver's callees side by side, then its increment beside the "
                           "detection")
    compiling.set_defaults(run=_compile)

    summary = commands.add_parser(
        "summary", help="one row per test: T/|N| at gross slips, wave counts, phases",
    )
    summary.add_argument("events", type=_input, nargs="+",
                         help="events netCDF files from 'slipwave detect --netcdf'")
    summary.add_argument("-o", "--output", type=Path, required=True, help="CSV to write")
    summary.set_defaults(run=_summary)

    kymo = commands.add_parser(
        "kymograph", help="kymograph of the band above the interface, from a video",
        description="Stream the frames of a video, image folder or TIFF stack, find (or "
        "take) the contact, and write the band's intensity, fringe activity and frame-to-"
        "frame change along the contact as netCDF.",
    )
    kymo.add_argument("frames", type=Path, help="video file, image folder or TIFF stack")
    kymo.add_argument("-o", "--output", type=Path, required=True, help="netCDF to write")
    kymo.add_argument("--test-id", default=None,
                      help="the test the video is of ('slipwave waves' then pairs it with that "
                      "test's recording only)")
    kymo.add_argument("--length", type=_setting("video", "length_mm"),
                      default=default.CONTACT_LENGTH_MM,
                      help="contact length, mm (%(default)s)")
    kymo.add_argument("--band", type=float, nargs=2, default=list(default.BAND_MM),
                      metavar=("LOW", "HIGH"), help="band above the interface, mm (%(default)s)")
    kymo.add_argument("--geometry", type=float, nargs=3, default=None,
                      metavar=("ROW", "LEFT", "RIGHT"),
                      help="interface row and the contact's end columns, px (found if not "
                      "given)")
    kymo.add_argument("--fps", type=_positive_float, default=None,
                      help="frame rate of sources without timestamps")
    kymo.add_argument("--keep-partial", action="store_true",
                      help="on a damaged video, keep the frames before the damage")
    kymo.set_defaults(run=_kymograph)

    waves = commands.add_parser(
        "waves", help="track the waves of a kymograph, align the clocks, pair with events",
    )
    waves.add_argument("kymograph", type=_input, help="netCDF from 'slipwave kymograph'")
    waves.add_argument("--recording", type=_input, required=True, help="recording netCDF")
    waves.add_argument("--events", type=_input, required=True, help="events netCDF")
    waves.add_argument("-o", "--output", type=Path, required=True, help="waves CSV to write")
    waves.add_argument("--fused", type=Path, required=True,
                       help="CSV of the events with their waves to write")
    waves.add_argument("--clock", type=Path, required=True, help="clock fit JSON to write")
    waves.set_defaults(run=_waves)

    sawtooth = commands.add_parser(
        "sawtooth", help="write three saw-tooth CSVs from a signal model (fixtures, demos)",
        description="Write three saw-tooth test CSVs (simple signal model, not the virtual "
        "bench), one of them in the vendor flavour.",
    )
    sawtooth.add_argument("output", type=Path, help="folder to write into")
    sawtooth.add_argument("--seed", type=_non_negative_int,
                          default=0, help="noise seed (default 0)")
    sawtooth.set_defaults(run=_sawtooth)

    slider_ingest = commands.add_parser(
        "slider-ingest", help="read a spring-slider record (MAT: t, Fnorm) into CF netCDF",
        description="Read a spring-slider record's MAT file and store it with its bench "
        "(stiffness, drive speed, mass, normal load), its role and its windows' length.")
    slider_ingest.add_argument("mat", type=_input, help="the MAT file (t, Fnorm)")
    slider_ingest.add_argument("-o", "--output", type=Path, required=True,
                               help="record netCDF to write")
    slider_ingest.add_argument("--record-id", required=True, help="the record's identifier")
    slider_ingest.add_argument("--role", choices=["fit", "predict"], required=True,
                               help="fit: fitted on; predict: only predicted")
    slider_ingest.add_argument("--stiffness", type=_positive_float, required=True,
                               help="the spring's stiffness, N/m")
    slider_ingest.add_argument("--drive-speed", type=_positive_float, required=True,
                               help="the drive's speed, um/s")
    slider_ingest.add_argument("--mass", type=_positive_float, required=True,
                               help="the slider's mass, g")
    slider_ingest.add_argument("--normal-load", type=_positive_float, default=None,
                               help="the normal load, N (default: the slider's weight)")
    slider_ingest.add_argument("--window", type=_positive_float, required=True,
                               help="the windows' length, s")
    slider_ingest.set_defaults(run=_slider_ingest)

    slider_fit = commands.add_parser(
        "slider-fit", help="fit rate-and-state friction to spring-slider records jointly",
        description="Fit a, b - a, log10 Dc and mu0 of rate-and-state friction (--evolution; "
        "and b2, log10 Dc2 of a second state with --states 2, log10 vc of a cut-off speed "
        "with --cutoff) "
        "to the records given, all at once, by a synthetic likelihood over their windows' "
        "features and a Gaussian-process search (slipwave.fit.slider).")
    slider_fit.add_argument("records", type=_input, nargs="+",
                            help="record netCDFs of 'slipwave slider-ingest' (role fit)")
    slider_fit.add_argument("-o", "--output", type=Path, required=True,
                            help="fit JSON to write (parameters, intervals)")
    slider_fit.add_argument("--posterior", type=Path, required=True,
                            help="posterior netCDF to write (samples, guesses)")
    for key in default.SLIDER_TUNABLES:
        if key != "draws":
            slider_fit.add_argument(
                f"--{key}", type=_setting("sliders", key), default=default.SLIDER_DEFAULTS[key],
                help=default.setting_schema("sliders", key)["description"].replace("%", "%%")
                + " (%(default)s)")
    slider_fit.add_argument("--evolution", choices=["aging", "slip"],
                            default=default.SLIDER_EVOLUTION,
                            help="the state's evolution law fitted (%(default)s)")
    slider_fit.add_argument(
        "--cutoff", action=argparse.BooleanOptionalAction, default=default.SLIDER_CUTOFF,
        help=default.setting_schema("sliders", "cutoff")["description"] + " (%(default)s)")
    slider_fit.add_argument("--processes", type=_positive_int, default=1,
                            help="worker processes for the guesses (%(default)s)")
    slider_fit.set_defaults(run=_slider_fit)

    slider_predict = commands.add_parser(
        "slider-predict", help="a spring-slider record's posterior predictive",
        description="Simulate the record's bench under posterior samples of the fit and say, "
        "feature by feature, whether the record lies in the predictive's 95 % interval, and "
        "which regime is predicted and measured.")
    slider_predict.add_argument("record", type=_input, help="record netCDF")
    slider_predict.add_argument("--posterior", type=_input, required=True,
                                help="posterior netCDF of 'slipwave slider-fit'")
    slider_predict.add_argument("-o", "--output", type=Path, required=True,
                                help="prediction JSON to write")
    slider_predict.add_argument("--draws", type=_setting("sliders", "draws"),
                                default=default.SLIDER_DEFAULTS["draws"],
                                help="posterior samples simulated (%(default)s)")
    slider_predict.add_argument("--members", type=_setting("sliders", "members"),
                                default=default.SLIDER_DEFAULTS["members"],
                                help="windows simulated per sample (%(default)s)")
    slider_predict.add_argument("--seed", type=_setting("sliders", "seed"),
                                default=default.SLIDER_DEFAULTS["seed"],
                                help="the draws' seed (%(default)s)")
    slider_predict.set_defaults(run=_slider_predict)

    slider_report = commands.add_parser(
        "slider-report", help="the spring-slider campaign's page: fit and predictions",
        description="Write the campaign's HTML page: the fitted law beside published values, "
        "and record by record the measured against the predicted regime, drop and recurrence.")
    slider_report.add_argument("--fit", type=_input, required=True, help="fit JSON")
    slider_report.add_argument("predictions", type=_input, nargs="+", help="prediction JSONs")
    slider_report.add_argument("-o", "--output", type=Path, required=True, help="HTML to write")
    slider_report.set_defaults(run=_slider_report)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status.

    Parameters
    ----------
    argv
        The arguments (``None``: ``sys.argv[1:]``).

    Returns
    -------
    int
        0 on success, 1 when slipwave reported an error in the input, 2 for an
        internal error (its traceback goes to a log file named on stderr), 130
        when interrupted (SIGINT or SIGTERM).

    """
    args = build_parser().parse_args(argv)
    previous = signal.signal(signal.SIGTERM, _terminate)
    try:
        args.run(args)
    except SlipwaveError as err:
        print(f"slipwave: error: {err}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("slipwave: interrupted; nothing half-written was kept", file=sys.stderr)
        return 130
    except Exception as err:  # a bug, not bad input: one line here, the traceback in a log
        log = _crash_log(err)
        print(f"slipwave: internal error ({type(err).__name__}: {err}); the full traceback "
              f"is in {log}; please report it with that file", file=sys.stderr)
        return 2
    finally:
        signal.signal(signal.SIGTERM, previous)
    return 0


UNWIND_SECONDS = 15.0
"""After SIGTERM, how long the command may take to unwind before it removes its part
files itself and ends (a scheduler sends SIGKILL some 30 s or more after SIGTERM)."""


def _terminate(signum: int, frame: object) -> None:
    # SIGTERM (a scheduler's or Snakemake's stop) unwinds like Ctrl-C: every output being
    # written is removed by its atomic_output on the way out. Should the unwinding stall
    # (CI once saw an ingest still running 60 s after the signal, its write interrupted
    # inside the netCDF library), a watchdog ends the process in its place.
    watchdog = threading.Timer(UNWIND_SECONDS, _give_up)
    watchdog.daemon = True
    watchdog.start()
    raise KeyboardInterrupt


def _give_up() -> None:
    """End the process now: the part files of its writes removed, exit status 130."""
    # read where loaded, not imported: importing slipwave.io costs the command line its
    # light start, and a process that never loaded it has no part files
    atomic = sys.modules.get("slipwave.io.atomic")
    if atomic is not None:
        atomic.remove_pending_parts()
    # os.write: the main thread, stuck, may hold sys.stderr's lock
    os.write(2, (f"slipwave: interrupted; nothing half-written was kept (the clean-up had "
                 f"not ended {UNWIND_SECONDS:g} s after the signal)\n").encode())
    os._exit(130)


def _crash_log(err: BaseException) -> Path:
    import tempfile
    import traceback

    fd, name = tempfile.mkstemp(prefix="slipwave-crash-", suffix=".log")
    with os.fdopen(fd, "w", encoding="utf-8") as handle:
        handle.write(f"slipwave {__version__}, command line: {sys.argv!r}\n\n")
        handle.write("".join(traceback.format_exception(err)))
    return Path(name)


if __name__ == "__main__":
    sys.exit(main())

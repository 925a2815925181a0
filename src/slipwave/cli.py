"""The ``slipwave`` command: one entry point, a subcommand per stage."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Literal

from slipwave import __version__
from slipwave.errors import SlipwaveError


def _column_pair(text: str) -> tuple[str, str]:
    header, equals, channel = text.rpartition("=")
    if not equals or not header:
        raise argparse.ArgumentTypeError(f"expected NAME=CHANNEL, got {text!r}")
    return header, channel


def _ingest(args: argparse.Namespace) -> None:
    from slipwave.io import read_acquisition, write_dataset

    recording = read_acquisition(args.raw, columns=dict(args.column) or None)
    write_dataset(recording, args.output)
    for warning in filter(None, recording.attrs["warnings"].splitlines()):
        print(f"warning: {args.raw}: {warning}", file=sys.stderr)
    print(f"{args.raw} -> {args.output}: {recording.sizes['time']} samples")


def _report(args: argparse.Namespace) -> None:
    from slipwave.io import read_dataset
    from slipwave.report import write_test_page

    write_test_page(read_dataset(args.recording), args.output)
    print(f"{args.recording} -> {args.output}")


def _synth(args: argparse.Namespace) -> None:
    from slipwave.io import write_acquisition
    from slipwave.synthetic import SawtoothBench, sawtooth_recording

    tests: list[tuple[SawtoothBench, Literal["canonical", "vendor"]]] = [
        (SawtoothBench(test_id="saw_hl050", height=40.0, ratio=1.0), "canonical"),
        (SawtoothBench(test_id="saw_hl025", height=20.0, ratio=0.9, stiffness=26.0,
                       gross_drops=(4.0, 6.0, 8.0), partial_drop=2.0), "canonical"),
        (SawtoothBench(test_id="saw_hl075", height=60.0, ratio=1.1, stiffness=16.0,
                       gross_drops=(6.0, 10.0, 14.0, 18.0), partial_drop=3.0), "vendor"),
    ]
    for k, (bench, flavour) in enumerate(tests):
        path = Path(args.output) / f"{bench.test_id}.csv"
        write_acquisition(sawtooth_recording(bench, seed=args.seed + k), path, flavour=flavour)
        print(f"{path} ({flavour})")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``slipwave`` (exposed for documentation and tests)."""
    parser = argparse.ArgumentParser(
        prog="slipwave", description="Friction-bench recordings to answers."
    )
    parser.add_argument("--version", action="version", version=f"slipwave {__version__}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    ingest = commands.add_parser(
        "ingest", help="read an acquisition CSV, write it as CF netCDF",
        description="Read an acquisition CSV (any supported dialect) and write it as "
        "compressed CF netCDF in N, mm and s.",
    )
    ingest.add_argument("raw", type=Path, help="acquisition CSV (opened read-only)")
    ingest.add_argument("-o", "--output", type=Path, required=True, help="netCDF to write")
    ingest.add_argument(
        "--column", type=_column_pair, action="append", default=[], metavar="NAME=CHANNEL",
        help="map a header name (without its unit) to time, index, T, N, DG, DD, DT or "
        "ignore; repeatable",
    )
    ingest.set_defaults(run=_ingest)

    report = commands.add_parser("report", help="write the HTML page of one test")
    report.add_argument("recording", type=Path, help="recording netCDF from 'slipwave ingest'")
    report.add_argument("-o", "--output", type=Path, required=True, help="HTML page to write")
    report.set_defaults(run=_report)

    synth = commands.add_parser(
        "synth", help="write the provisional saw-tooth campaign (three CSVs)",
        description="Write three saw-tooth test CSVs (simple signal model, not the virtual "
        "bench), one of them in the vendor flavour.",
    )
    synth.add_argument("output", type=Path, help="folder to write into")
    synth.add_argument("--seed", type=int, default=0, help="noise seed (default 0)")
    synth.set_defaults(run=_synth)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status."""
    args = build_parser().parse_args(argv)
    try:
        args.run(args)
    except SlipwaveError as err:
        print(f"slipwave: error: {err}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())

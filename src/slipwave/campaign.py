"""The campaign table and config of the workflow, read for Snakemake and the CLI."""

from __future__ import annotations

import shlex
from collections.abc import Iterable, Mapping
from os import PathLike
from pathlib import Path
from typing import Any

import pandas as pd

from slipwave.errors import ConfigError
from slipwave.validation import check, read_yaml, setup_value_problem

SETUP_COLUMNS = ("length_mm", "height_mm", "width_mm", "youngs_modulus_mpa", "poisson_ratio",
                 "normal_load_n", "speed_mm_s", "machine_stiffness_n_mm", "edge_reference")
"""Columns of a test's configuration for its simulation (:mod:`slipwave.setup`)."""

OPTIONAL_COLUMNS = ("frames", "columns", "fps", "edge_convention", "height_ratio",
                    *SETUP_COLUMNS)
"""Columns a campaign table may leave out (their cells are then empty)."""


RESERVED_TEST_IDS = {
    "campaign": "reports/campaign.html",
    "summary.csv": "results/summary.csv",
    "fits.csv": "results/fits.csv",
    "fits.png": "results/fits.png",
    "map": "results/map/",
    "logs": "results/logs/",
    "cache": "results/cache/",
    "solver.json": "results/solver.json",
    "sliders": "results/sliders/ and reports/sliders.html (a spring-slider campaign)",
}
"""Names of the campaign's own products beside the tests' (a test's files are
``results/<test_id>/`` and ``reports/<test_id>.html``): no test may take one."""


def read_campaign(path: str | PathLike[str]) -> pd.DataFrame:
    r"""Read a campaign table (tab separated, one row per test), indexed by ``test_id``.

    Lines whose first character (after blanks) is ``#`` are comments and blank
    lines are skipped; the first other line is the header. Cells are stripped of
    surrounding blanks; missing trailing cells and the optional columns
    (:data:`OPTIONAL_COLUMNS`) are empty strings.

    Parameters
    ----------
    path
        The table (UTF-8).

    Returns
    -------
    pandas.DataFrame
        One row per test, all cells text, indexed by ``test_id``; ``attrs``
        holds ``source`` (the path) and ``lines`` (test id -> its line in the file).

    Raises
    ------
    ConfigError
        If the file is missing or not text, has no test, lacks a required
        column, has a row longer than its header or repeats a test id (naming
        the line).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> table = pathlib.Path(tempfile.mkdtemp()) / "tests.tsv"
    >>> _ = table.write_text("# my campaign\ntest_id\tcsv\nrun01\t/data/run01.csv\n")
    >>> campaign = read_campaign(table)
    >>> campaign.loc["run01", "csv"], campaign.loc["run01", "frames"], campaign.attrs["lines"]
    ('/data/run01.csv', '', {'run01': 3})
    """
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError as err:
        raise ConfigError(f"{path}: campaign table not found") from err
    except IsADirectoryError as err:
        raise ConfigError(f"{path}: is a directory, not a campaign table") from err
    except OSError as err:
        raise ConfigError(f"{path}: cannot be read: {err.strerror}") from err
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        line = 1 + raw[: err.start].count(b"\n")
        raise ConfigError(f"{path}, line {line}: not UTF-8 text ({err.reason})") from err
    rows: list[list[str]] = []
    lines: list[int] = []
    for number, line_text in enumerate(text.splitlines(), start=1):
        if not line_text.strip() or line_text.lstrip().startswith("#"):
            continue
        cells = [cell.strip() for cell in line_text.split("\t")]
        if rows:
            width = len(rows[0])
            if any(cells[width:]):
                raise ConfigError(f"{path}, line {number}: {len(cells)} cells where the header "
                                  f"has {width}")
            cells = cells[:width] + [""] * (width - len(cells))
        rows.append(cells)
        lines.append(number)
    if not rows:
        raise ConfigError(f"{path}: no header row: the table is empty or only comments")
    header = rows[0]
    for required in ("test_id", "csv"):
        if required not in header:
            raise ConfigError(
                f"{path}, line {lines[0]}: no {required!r} column; the header names "
                f"{', '.join(map(repr, header))}"
            )
    repeated = next((name for k, name in enumerate(header) if name in header[:k]), None)
    if repeated is not None:
        raise ConfigError(f"{path}, line {lines[0]}: column {repeated!r} appears twice")
    if len(rows) == 1:
        raise ConfigError(f"{path}: no test: the table has a header but no row")
    table = pd.DataFrame(rows[1:], columns=header, dtype=str)
    for optional in OPTIONAL_COLUMNS:
        if optional not in table.columns:
            table[optional] = ""
    seen: dict[str, int] = {}
    for test_id, number in zip(table["test_id"], lines[1:], strict=True):
        if test_id in seen:
            raise ConfigError(f"{path}, line {number}: test_id {test_id!r} appears twice "
                              f"(first on line {seen[test_id]})")
        seen[test_id] = number
    table = table.set_index("test_id", drop=False)
    table.attrs = {"source": str(path), "lines": seen}
    return table


def column_map(config: Mapping[str, Any], name: str) -> dict[str, str]:
    """The column mapping called ``name`` in the config.

    Parameters
    ----------
    config
        The workflow's config (its ``column_maps``).
    name
        The map's name; empty for none.

    Returns
    -------
    dict
        Header name (without its unit) -> channel; empty for no name.

    Raises
    ------
    ConfigError
        If the config has no map of that name.

    """
    if not name:
        return {}
    maps = config.get("column_maps") or {}
    if name not in maps:
        known = ", ".join(map(repr, maps)) or "none"
        raise ConfigError(f"column map {name!r} is not in the config's column_maps ({known})")
    return {str(k): str(v) for k, v in maps[name].items()}


def cache_option(config: Mapping[str, Any]) -> str:
    """The command-line option that names the config's ``cache_dir`` (none for null).

    Parameters
    ----------
    config
        The validated workflow config (``cache_dir`` filled in).

    Returns
    -------
    str
        ``--cache-dir FOLDER`` (quoted for a shell), or an empty string.

    Examples
    --------
    >>> cache_option({"cache_dir": "results/my cache"})
    "--cache-dir 'results/my cache'"
    >>> cache_option({"cache_dir": None})
    ''
    """
    folder = config["cache_dir"]
    return f"--cache-dir {shlex.quote(str(folder))}" if folder else ""


def column_pairs(config: Mapping[str, Any], name: str) -> list[str]:
    """The column map called ``name`` as ``NAME=CHANNEL`` values of ``slipwave ingest --columns``.

    Parameters
    ----------
    config
        The workflow's config.
    name
        A test's ``columns`` cell (empty: no map).

    Returns
    -------
    list of str
        One ``header=channel`` per mapped column.

    Examples
    --------
    >>> column_pairs({"column_maps": {"lab": {"Zeit": "time", "Kraft x": "T"}}}, "lab")
    ['Zeit=time', 'Kraft x=T']
    """
    return [f"{header}={channel}" for header, channel in column_map(config, name).items()]


def setup_cells(test: Mapping[str, str] | pd.Series) -> list[str]:
    """``COLUMN=VALUE`` for each configuration cell a test fills (``slipwave fit --setting``).

    Parameters
    ----------
    test
        The test's row of the campaign table.

    Returns
    -------
    list of str
        One pair per non-empty cell of :data:`SETUP_COLUMNS`, in that order.

    Examples
    --------
    >>> setup_cells({"height_mm": "40", "edge_reference": "frame", "width_mm": ""})
    ['height_mm=40', 'edge_reference=frame']
    """
    return [f"{column}={test.get(column)}" for column in SETUP_COLUMNS
            if str(test.get(column) or "").strip()]


def edge_convention(config: Mapping[str, Any], test: Mapping[str, str] | pd.Series) -> str:
    """A test's edge-sensor convention: its table cell, else the config's.

    Parameters
    ----------
    config
        The validated workflow config (``detection.edge_convention`` filled in).
    test
        The test's row of the campaign table.

    Returns
    -------
    str
        ``auto``, ``x_axis`` or ``outward``.

    Examples
    --------
    >>> edge_convention({"detection": {"edge_convention": "auto"}}, {"edge_convention": "outward"})
    'outward'
    """
    return str(test.get("edge_convention") or config["detection"]["edge_convention"])


STAGES_READ: dict[str, tuple[str, ...]] = {"fit_waves": ("fit", "simulate_waves")}
"""A stage's config section -> the sections of the stages whose products it reads."""


def check_stages(config: Mapping[str, Any]) -> None:
    """Refuse a stage enabled without a stage it reads.

    Parameters
    ----------
    config
        The validated workflow config.

    Raises
    ------
    ConfigError
        Naming the setting and the stages it needs.

    Examples
    --------
    >>> check_stages({"fit": {"enabled": False}, "simulate_waves": {"enabled": True},
    ...               "fit_waves": {"enabled": True}})
    Traceback (most recent call last):
    ...
    slipwave.errors.ConfigError: fit_waves.enabled: true needs fit.enabled ...
    """
    for stage, needed in STAGES_READ.items():
        if not config[stage]["enabled"]:
            continue
        for other in needed:
            if not config[other]["enabled"]:
                raise ConfigError(f"{stage}.enabled: true needs {other}.enabled (its products "
                                  f"are read); set it true or {stage}.enabled false")


def check_campaign(config: Mapping[str, Any], campaign: pd.DataFrame,
                   schema: Mapping[str, Any] | None = None) -> None:
    """Check each test of the campaign: its cells, its column map and its settings.

    Parameters
    ----------
    config
        The validated workflow config.
    campaign
        From :func:`read_campaign`.
    schema
        The table's schema (``slipwave/schemas/tests.schema.json``): each row
        is checked against it, and an error names the table's file and line.

    Raises
    ------
    ConfigError
        Naming the file, the line, the test and what is wrong, before any job starts.

    """
    source = campaign.attrs.get("source", "the campaign table")
    lines = campaign.attrs.get("lines", {})
    folded: dict[str, str] = {}
    for test_id, test in campaign.iterrows():
        where = f"{source}, line {lines[test_id]}" if test_id in lines else source
        where += f" (test {test_id!r})"
        if schema is not None:
            check(dict(test), dict(schema), source=where)
        if str(test_id).lower() in RESERVED_TEST_IDS:
            raise ConfigError(f"{where}: test_id {test_id!r} is the name of a campaign product "
                              f"({RESERVED_TEST_IDS[str(test_id).lower()]}): rename the test")
        other = folded.setdefault(str(test_id).lower(), str(test_id))
        if other != test_id:
            raise ConfigError(f"{where}: test_id {test_id!r} differs from {other!r} only by "
                              "case: their files would be one on a case-insensitive disk")
        for key in SETUP_COLUMNS:
            cell = str(test.get(key, "") or "")
            problem = setup_value_problem(key, cell) if cell and key != "edge_reference" else None
            if problem is not None:
                raise ConfigError(f"{where}: {key}: {problem}")
        try:
            column_map(config, test["columns"])
        except ConfigError as err:
            raise ConfigError(f"{where}: {err}") from err


def check_config_files(paths: Iterable[str | PathLike[str]],
                       schema: Mapping[str, Any] | None = None, *,
                       command_line: Iterable[str | PathLike[str]] = ()) -> dict[str, Any]:
    """Check the workflow's config files one by one, before Snakemake merges them.

    Each file's own settings are checked against the config schema, so that an
    error names the file and the line (Snakemake's check of the merged config
    cannot). And Snakemake merges ``--configfile`` files over the workflow's own
    config: if none of those sets ``tests`` (or ``kind: spring_slider``, a campaign of
    spring-slider records), the default campaign would silently run.

    Parameters
    ----------
    paths
        Every config file (the workflow's own and the command line's).
    schema
        ``slipwave/schemas/config.schema.json``; ``None``: only the rule on ``tests``.
    command_line
        The ``--configfile`` files (Snakemake's ``workflow.overwrite_configfiles``).

    Returns
    -------
    dict
        The files' settings merged in order, mapping by mapping, as Snakemake merges
        them (without the schema's defaults).

    Raises
    ------
    ConfigError
        Naming the file, the line, the setting and what is wrong.

    """
    settings = None if schema is None else {key: value for key, value in schema.items()
                                            if key != "required"}
    contents = {}
    for path in paths:
        content, line_of = read_yaml(path)
        contents[Path(path)] = content
        if settings is not None:
            check(content or {}, settings, source=str(path), line_of=line_of)
    given = [Path(p) for p in command_line]
    # a campaign of its own: slab tests, or spring-slider records (kind spring_slider)
    if given and not any(isinstance(contents.get(path), Mapping)
                         and (contents[path].get("tests")
                              or contents[path].get("kind") == "spring_slider")
                         for path in given):
        names = ", ".join(map(str, given))
        raise ConfigError(f"{names}: no 'tests' entry naming the campaign table (nor kind: "
                          "spring_slider); without it the default campaign "
                          "(config/config.yaml) would run instead")
    merged: dict[str, Any] = {}
    for content in contents.values():
        _merge(merged, content or {})
    return merged


def _merge(into: dict[str, Any], update: Mapping[str, Any]) -> None:
    """Merge ``update`` into ``into``, mapping by mapping (Snakemake's update_config)."""
    for key, value in update.items():
        if isinstance(value, Mapping) and isinstance(into.get(key), dict):
            _merge(into[key], value)
        else:
            into[key] = dict(value) if isinstance(value, Mapping) else value


def height_ratio_pairs(campaign: pd.DataFrame) -> list[str]:
    """``TEST=H/L`` for each test with a ``height_ratio`` (for ``slipwave map assemble``).

    Parameters
    ----------
    campaign
        From :func:`read_campaign`.

    Returns
    -------
    list of str
        One pair per test that has an H/L, in table order.

    Examples
    --------
    >>> table = pd.DataFrame({"test_id": ["a", "b"], "height_ratio": ["0.5", ""]})
    >>> height_ratio_pairs(table)
    ['a=0.5']
    """
    return [f"{test}={ratio}" for test, ratio in zip(campaign["test_id"],
                                                     campaign["height_ratio"], strict=True)
            if str(ratio)]

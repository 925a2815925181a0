"""Settings checked against the JSON schemas slipwave ships, with errors naming where.

The schemas (``slipwave/schemas/*.json``, draft 2020-12) are the one statement of
what a setting may be; this module applies them and turns the first violation into a
:class:`~slipwave.errors.ConfigError` naming the file, the line when known, the
setting and what is wrong.
"""

from __future__ import annotations

import functools
import json
import math
from collections.abc import Callable, Sequence
from importlib import resources
from os import PathLike
from pathlib import Path
from typing import Any

import jsonschema
import referencing
import yaml

from slipwave.errors import ConfigError


@functools.cache
def schema_path(name: str) -> Path:
    """Where a schema shipped with slipwave lies (the workflow validates against it).

    Parameters
    ----------
    name
        Its file name without ``.schema.json`` (``"config"``, ``"tests"``, ``"bench"``).

    Returns
    -------
    Path
        The file, inside the installed package.

    """
    return Path(str(resources.files("slipwave").joinpath(f"schemas/{name}.schema.json")))


def load_schema(name: str) -> dict[str, Any]:
    """A schema shipped with slipwave.

    Parameters
    ----------
    name
        Its file name without ``.schema.json`` (e.g. ``"bench"``).

    Returns
    -------
    dict
        The schema.

    """
    return dict(json.loads(schema_path(name).read_text()))


@functools.cache
def _registry() -> referencing.Registry:
    """The shipped schemas, by their ``$id``: one schema may refer to another's settings."""
    resources_by_id = []
    for path in sorted(schema_path("config").parent.glob("*.schema.json")):
        contents = json.loads(path.read_text())
        resources_by_id.append((contents["$id"], referencing.Resource.from_contents(contents)))
    return referencing.Registry().with_resources(resources_by_id)


@functools.cache
def _setup_numbers() -> dict[str, dict[str, Any]]:
    return {key: item["x-number"] for key, item in load_schema("tests")["properties"].items()
            if "x-number" in item}


def setup_value_problem(key: str, text: object) -> str | None:
    """What is wrong with a value of a test's setup, or ``None``.

    The campaign table's cells and the recording header's values of the same names
    (``length_mm``, ``poisson_ratio``...) are held to one schema: the campaign
    table's ``x-number``.

    Parameters
    ----------
    key
        The column (or header key).
    text
        Its value, as written.

    Returns
    -------
    str or None
        The problem in words.

    Examples
    --------
    >>> setup_value_problem("poisson_ratio", "0.48") is None
    True
    >>> setup_value_problem("poisson_ratio", "0.6")
    '0.6 is greater than or equal to the maximum of 0.5'
    >>> setup_value_problem("height_mm", "abc")
    "'abc' is not a number"
    """
    try:
        value = float(str(text).strip())
    except ValueError:
        return f"{str(text).strip()!r} is not a number"
    if not math.isfinite(value):
        return f"{value} is not a finite number"
    schema = _setup_numbers().get(key, {})
    error = jsonschema.exceptions.best_match(
        jsonschema.Draft202012Validator(schema).iter_errors(value))
    return None if error is None else str(error.message)


def describe_path(path: Sequence[str | int], document: Any = None) -> str:
    """A setting's place in a document, as a reader writes it.

    Parameters
    ----------
    path
        Keys and list indices from the top.
    document
        The document, to name a list entry by its ``test_id`` where it has one.

    Returns
    -------
    str
        e.g. ``tests[1] (test 'hl050').camera.fps``; ``the top level`` for an
        empty path.

    Examples
    --------
    >>> describe_path(["tests", 1, "camera", "fps"])
    'tests[1].camera.fps'
    >>> describe_path(["tests", 0, "fs"], {"tests": [{"test_id": "hl050"}]})
    "tests[0] (test 'hl050').fs"
    """
    text = ""
    node = document
    for part in path:
        text += f"[{part}]" if isinstance(part, int) else f".{part}"
        try:
            node = node[part] if node is not None else None
        except (KeyError, IndexError, TypeError):
            node = None
        if isinstance(part, int) and isinstance(node, dict) and "test_id" in node:
            text += f" (test {node['test_id']!r})"
    return text.lstrip(".") or "the top level"


def check(instance: Any, schema: dict[str, Any], *, source: str,
          line_of: Callable[[Sequence[str | int]], int | None] | None = None) -> None:
    """Raise on the first place where ``instance`` breaks ``schema``.

    Parameters
    ----------
    instance
        The settings (mappings, lists, scalars).
    schema
        A draft 2020-12 schema.
    source
        What the settings came from, for the message (a file name).
    line_of
        Gives the line of a setting from its path, when the source has lines.

    Raises
    ------
    ConfigError
        ``<source>, line <n>: <setting>: <what is wrong>``.

    """
    validator = jsonschema.Draft202012Validator(schema, registry=_registry())
    error = jsonschema.exceptions.best_match(validator.iter_errors(instance))
    if error is None:
        return
    path = list(error.absolute_path)
    line = line_of(path) if line_of is not None else None
    where = f"{source}, line {line}" if line is not None else source
    raise ConfigError(f"{where}: {describe_path(path, instance)}: {error.message}")


def read_yaml(path: str | PathLike[str]) -> tuple[Any, Callable[[Sequence[str | int]], int | None]]:
    """A YAML file's content and a function giving the line of a setting in it.

    Parameters
    ----------
    path
        The file.

    Returns
    -------
    tuple
        The content (as ``yaml.safe_load`` gives it) and ``line_of(path)``.

    Raises
    ------
    ConfigError
        If the file cannot be read or is not YAML (naming the line).

    """
    try:
        text = Path(path).read_text(encoding="utf-8")
        node = yaml.compose(text, Loader=yaml.SafeLoader)
        content = yaml.safe_load(text)
    except (OSError, UnicodeDecodeError) as err:
        raise ConfigError(f"{path}: cannot be read: {err}") from err
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f"{path}, line {mark.line + 1}" if mark is not None else str(path)
        raise ConfigError(f"{where}: not valid YAML: {getattr(err, 'problem', err)}") from err

    def line_of(keys: Sequence[str | int]) -> int | None:
        current = node
        for key in keys:
            if isinstance(current, yaml.MappingNode):
                found = [v for k, v in current.value if k.value == key]
                if not found:
                    break
                current = found[0]
            elif isinstance(current, yaml.SequenceNode) and isinstance(key, int) \
                    and key < len(current.value):
                current = current.value[key]
            else:
                break
        return None if current is None else current.start_mark.line + 1

    return content, line_of


def read_json(path: str | PathLike[str], schema: str) -> dict[str, Any]:
    """A JSON product of slipwave's, held to its schema.

    Parameters
    ----------
    path
        The file.
    schema
        The shipped schema's name (``"fit"``, ``"comparison"``).

    Returns
    -------
    dict
        Its content.

    Raises
    ------
    ConfigError
        ``<path>, line <n>, column <m>: not valid JSON`` or ``<path>: <key>: <what is
        wrong>``.

    """
    try:
        with open(path, encoding="utf-8") as stream:
            content = json.load(stream)
    except json.JSONDecodeError as err:
        raise ConfigError(f"{path}, line {err.lineno}, column {err.colno}: not valid JSON "
                          f"({err.msg})") from err
    except UnicodeDecodeError as err:
        raise ConfigError(f"{path}: not UTF-8 text, not JSON") from err
    except FileNotFoundError as err:
        raise ConfigError(f"{path}: no such file") from err
    except OSError as err:
        raise ConfigError(f"{path}: cannot be read: {err.strerror}") from err
    loaded = load_schema(schema)
    try:
        check(content, loaded, source=str(path))
    except ConfigError as err:
        raise ConfigError(f"{err} (not the {schema} JSON slipwave writes, or edited)") from err
    return dict(content)

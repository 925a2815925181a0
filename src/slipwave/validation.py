"""Settings checked against the JSON schemas slipwave ships, with errors naming where.

The schemas (``slipwave/schemas/*.json``, draft 2020-12) are the one statement of
what a setting may be; this module applies them and turns the first violation into a
:class:`~slipwave.errors.ConfigError` naming the file, the line when known, the
setting and what is wrong.
"""

from __future__ import annotations

import functools
import json
from collections.abc import Callable, Sequence
from importlib import resources
from os import PathLike
from pathlib import Path
from typing import Any

import jsonschema
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
    validator = jsonschema.Draft202012Validator(schema)
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

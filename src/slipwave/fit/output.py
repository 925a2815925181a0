"""A fit's output: ``fit.json``, read back checked, and the law it chose.

:func:`~slipwave.fit.procedure.fit_test` writes the content; :func:`read_fit` holds a
file to ``slipwave/schemas/fit.schema.json`` and to what a schema cannot say.
"""

from __future__ import annotations

from collections.abc import Mapping
from os import PathLike
from typing import Any

from slipwave.errors import SlipwaveError
from slipwave.fit.laws import LAWS, law_of
from slipwave.setup import GEOMETRY, TestSetup
from slipwave.solver import Coulomb
from slipwave.validation import read_json, setup_value_problem


def chosen_law(fit: Mapping[str, Any]) -> Coulomb:
    """The solver's law of a fit's chosen law (``fit.json`` as a mapping).

    Parameters
    ----------
    fit
        From :func:`~slipwave.fit.procedure.fit_test` (or its JSON).

    Returns
    -------
    Coulomb
        The law.

    """
    return law_of(fit["chosen"], fit["parameters"])


def read_fit(path: str | PathLike[str]) -> dict[str, Any]:
    """A ``fit.json``, checked, with an error naming the file and the key when it is not one.

    The file is held to ``slipwave/schemas/fit.schema.json``, and what a schema cannot
    say is checked too: the chosen law is one of the fitted laws, its parameters are
    that law's and make a law the solver takes, and the setup is a slab's.

    Parameters
    ----------
    path
        The file.

    Returns
    -------
    dict
        Its content (:func:`~slipwave.fit.procedure.fit_test`).

    Raises
    ------
    SlipwaveError
        ``<path>: <key>: <what is wrong>`` (or the line and column of broken JSON).

    """
    fit = read_json(path, "fit")
    chosen = fit["chosen"]
    if chosen not in fit["laws"]:
        raise SlipwaveError(f"{path}: chosen: {chosen!r} is not one of the fitted laws "
                            f"{sorted(fit['laws'])}")
    names = set(LAWS[chosen])
    for where, values in [("parameters", fit["parameters"]),
                          (f"laws.{chosen}.parameters", fit["laws"][chosen]["parameters"])]:
        if set(values) != names:
            raise SlipwaveError(f"{path}: {where}: {sorted(values)} are not the parameters of "
                                f"the {chosen} law, {sorted(names)}")
    try:
        law_of(chosen, fit["parameters"])
        setup = TestSetup.from_dict(fit["setup"])
        for key in GEOMETRY:
            problem = setup_value_problem(key, setup[key])
            if problem is not None:
                raise SlipwaveError(f"setup.{key}.value: {problem}")
        setup.slab(int(fit["elements"]))
    except SlipwaveError as err:
        raise SlipwaveError(f"{path}: {err}") from err
    return dict(fit)

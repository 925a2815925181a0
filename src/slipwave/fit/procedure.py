"""A test's fit: each law's posterior, the law chosen by its evidence, its predictive check.

:func:`fit_test` runs the laws in order (Coulomb first: the richer laws search around
its posterior), each by :func:`~slipwave.fit.law_search.search_law` on the test's synthetic
likelihood (:mod:`slipwave.fit.ensemble`, :mod:`slipwave.fit.likelihood`). The law of
highest evidence is chosen; its posterior predictive (:func:`predictive_check`) says
feature by feature whether the measurement lies within the spread of the law's
simulations, and a local search at twice the mesh (:func:`mesh_check`) how far its
parameters still follow the mesh.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import partial
from typing import Any

import numpy as np
import pandas as pd
from scipy.stats import norm

from slipwave.defaults import (
    FIT_DEFAULTS,
    FIT_ELEMENTS,
    FIT_MESH_CHECK,
    LOAD_CALIBRATION,
)
from slipwave.errors import SlipwaveError
from slipwave.events.detect import DEFAULT_DETECTION, DetectionSettings
from slipwave.fit.ensemble import Ensemble, Nuisances, draw_members, mesh_error
from slipwave.fit.features import (
    FEATURES,
    detected_edge_threshold,
    gross_by_edges,
    measured_split,
    measurement_error,
)
from slipwave.fit.law_search import posterior_box, search_law
from slipwave.fit.laws import (
    LAWS,
    PRIORS,
    STATIC_EXCESS,
    UNITS,
    ZONE_ELEMENTS,
    law_of,
    prior_bounds,
)
from slipwave.fit.likelihood import SyntheticLikelihood
from slipwave.fit.search import Posterior, SearchSettings
from slipwave.setup import TestSetup
from slipwave.solver import Coulomb, SlipWeakening, SolverCache


@dataclass(frozen=True)
class FitSettings:
    """Everything a fit takes besides the test (the configuration's ``fit`` section).

    Attributes
    ----------
    elements
        Elements along the contact.
    members
        Simulations per guess (the ensemble).
    nuisances
        What the recording does not fix, and how uncertain it is.
    ratio_error, time_error
        The measured features' own standard errors (a T/|N|; a time, s).
    search
        How far each law's search goes.
    predictive_members
        Simulations of the chosen law's posterior predictive.
    mesh_check
        Search the chosen law again at twice ``elements``.

    """

    elements: int
    members: int
    nuisances: Nuisances
    ratio_error: float
    time_error: float
    search: SearchSettings
    predictive_members: int
    mesh_check: bool

    @classmethod
    def from_values(cls, values: Mapping[str, Any]) -> FitSettings:
        """The settings from the configuration's ``fit`` keys, defaults for the others.

        Parameters
        ----------
        values
            ``elements``, ``load_calibration``, ``mesh_check`` and any of
            :data:`~slipwave.defaults.FIT_TUNABLES` (a campaign's ``fit`` section, or a
            command line's options).

        Returns
        -------
        FitSettings
            The settings.

        Examples
        --------
        >>> FitSettings.from_values({"members": 6}).members
        6
        """
        defaults = {**FIT_DEFAULTS, "elements": FIT_ELEMENTS,
                    "load_calibration": LOAD_CALIBRATION, "mesh_check": FIT_MESH_CHECK}
        v = {key: values.get(key, default) for key, default in defaults.items()}
        return cls(elements=int(v["elements"]), members=int(v["members"]),
                   nuisances=Nuisances(float(v["load_calibration"]), float(v["stiffness_error"]),
                                       float(v["speed_error"]), float(v["step_jitter"])),
                   ratio_error=float(v["ratio_error"]), time_error=float(v["time_error_s"]),
                   search=SearchSettings(int(v["design"]), int(v["refinements"]),
                                         float(v["draw_temperature"]), int(v["samples"]),
                                         int(v["seed"])),
                   predictive_members=int(v["predictive_members"]),
                   mesh_check=bool(v["mesh_check"]))


FD_WINDOW = 0.1
"""Half-width of Coulomb's first search box in fd about T/|N| after the largest drops:
a gross slip overshoots fd by a few hundredths at most (the slab's inertia-free
unloading, a sampled trough), never by a tenth."""
SEARCH_MARGIN = {"fs": (0.15, 0.25), "fd": (0.02, 0.02), "fs_final": (0.4, 0.4)}
"""How far the richer laws' first box reaches beyond Coulomb's 95 % interval (below,
above): a run-in's first and final fs lie either side of Coulomb's fs. A slip-weakening
law's fs reaches down to the prior's floor instead (:func:`first_box`)."""
FAMILY_LEVEL = 0.95
"""The predictive check's level over all features at once: each feature's band is
Bonferroni's, z of 1 - (1 - level) / (2 features)."""


def band_z(features: int) -> float:
    """The predictive band's half-width, in standard deviations, for so many features.

    Parameters
    ----------
    features
        How many features are checked at once.

    Returns
    -------
    float
        z of 1 - (1 - :data:`FAMILY_LEVEL`) / (2 features) (Bonferroni).

    Examples
    --------
    >>> round(band_z(13), 2)
    2.89
    """
    return float(norm.ppf(1.0 - (1.0 - FAMILY_LEVEL) / (2 * max(1, features))))


def probe_threshold(setup: TestSetup, measured: pd.DataFrame, *, elements: int,
                    detection: DetectionSettings = DEFAULT_DETECTION,
                    cache: SolverCache | None = None) -> float:
    """The test's edge threshold from one Coulomb run at plausible coefficients.

    What separates a gross slip's edge jumps from a partial slip's is the slab's shape
    (how the far edge follows); one simulation at fd from the largest drops and fs 0.3
    above sets it for the whole fit. A law whose gross slips move the far edge less
    than Coulomb's (slip-weakening with a small excess: DG/DD 1.2 where Coulomb's probe
    puts the threshold at 1.6) would then show no gross slip at all in a test sheared
    until it slides: where no measured slip reaches the probe's threshold, the
    measured ratios' own clear split is taken
    (:func:`~slipwave.fit.features.measured_split`), if they have one.

    Parameters
    ----------
    setup, measured, elements, detection, cache
        As in :func:`fit_test`.

    Returns
    -------
    float
        :func:`~slipwave.fit.features.detected_edge_threshold` of that run, or the
        measured split.

    """
    fd = fd_start(measured)
    simulation = setup.simulate(Coulomb(fs=fd + 0.3, fd=fd), elements, cache=cache)
    threshold = detected_edge_threshold(simulation, setup,
                                        min_drop=float(measured.attrs.get("min_drop", 0.0)),
                                        sample_rate=float(measured.attrs["sample_rate"]),
                                        detection=detection)
    if gross_by_edges(measured, threshold).any():
        return threshold
    split = measured_split(measured)
    return threshold if split is None else split


def fd_start(measured: pd.DataFrame) -> float:
    """T/|N| after the largest quarter of the drops, within fd's prior.

    Parameters
    ----------
    measured
        The test's events.

    Returns
    -------
    float
        Where Coulomb's search centres fd.

    """
    largest = measured["drop"] >= measured["drop"].quantile(0.75)
    return float(np.clip(measured.loc[largest, "ratio_after"].median(), PRIORS["fd"].low,
                         PRIORS["fd"].high))


def dc_per_excess(setup: TestSetup, elements: int) -> float:
    """The shortest Dc the mesh resolves, per unit of fs - fd.

    A slip-weakening law's process zone, G* Dc / ((fs - fd) sigma), must span
    :data:`~slipwave.fit.laws.ZONE_ELEMENTS` elements: Dc at least this times fs - fd.

    Parameters
    ----------
    setup
        The test's setup.
    elements
        The mesh.

    Returns
    -------
    float
        mm per unit of fs - fd.

    """
    spacing = setup["length_mm"] / elements
    zone = setup.process_zone(SlipWeakening(fs=1.0, fd=0.0, dc=1.0))  # Dc 1 mm, excess 1
    return ZONE_ELEMENTS * spacing / zone


def first_box(law: str, measured: pd.DataFrame, coulomb: Posterior | None) -> np.ndarray:
    """Where a law's search starts, in its prior's coordinates.

    Coulomb: fd within :data:`FD_WINDOW` of T/|N| after the largest drops, fs over its
    prior. The others: around Coulomb's posterior (:data:`SEARCH_MARGIN`), their own
    parameters over their priors; without Coulomb's, as Coulomb's.

    Parameters
    ----------
    law
        One of :data:`~slipwave.fit.laws.LAWS`.
    measured
        The test's events.
    coulomb
        Coulomb's posterior, if fitted.

    Returns
    -------
    numpy.ndarray
        Shape (parameters, 2).

    """
    box = prior_bounds(law)
    names = LAWS[law]
    fd = fd_start(measured)
    box[names.index("fd")] = (fd - FD_WINDOW, fd + FD_WINDOW)
    if coulomb is None:
        return box
    summary = coulomb.summary()
    for name in ("fs", "fd"):
        below, above = SEARCH_MARGIN[name]
        box[names.index(name)] = (summary[name]["low"] - below, summary[name]["high"] + above)
    if law == "slip-weakening":
        # A gross slip shorter than Dc stops above fd: its fd lies at or below the
        # T/|N| after the largest drops and Coulomb's fd (which a Coulomb law that
        # fits badly can leave far from it: 0.51 for a measured 0.42), by FD_WINDOW.
        box[names.index("fd")] = (min(summary["fd"]["low"], fd) - FD_WINDOW,
                                  max(summary["fd"]["high"], fd) + SEARCH_MARGIN["fd"][1])
        # Its fs lies below Coulomb's, by up to 0.45 in a calibration set (6 tests of
        # 7): where Coulomb's corner node gives way at once, a weakening one keeps its
        # load over Dc, so the contact reaches the same peak T/|N| from a lower fs.
        # Down to the prior's floor, fd plus the least static excess.
        box[names.index("fs")][0] = box[names.index("fd")][0] + STATIC_EXCESS[0]
    if "fs_final" in names:
        below, above = SEARCH_MARGIN["fs_final"]
        box[names.index("fs_final")] = (summary["fs"]["low"] - below,
                                        summary["fs"]["high"] + above)
    return box


def predictive_check(ensemble: Ensemble, posterior: Posterior, members: int, seed: int,
                     error: np.ndarray) -> dict[str, dict[str, Any]]:
    """The chosen law's posterior predictive against the measured features.

    ``members`` simulations, each with parameters drawn from the posterior and its own
    nuisances (:func:`~slipwave.fit.ensemble.draw_members`); a feature agrees when
    the measurement lies within z standard deviations of their mean, the spread of the
    simulations, the measurement's own error and the mesh's (the posterior's
    ``model_error``) in quadrature (ASME V&V 20's validation uncertainty), z Bonferroni's for
    :data:`FAMILY_LEVEL` over all the features: a law that is right then agrees on every
    feature in 95 % of tests.

    Parameters
    ----------
    ensemble
        The test's ensemble (its setup, measurement and settings).
    posterior
        The chosen law's.
    members
        Simulations.
    seed
        The draws' seed.
    error
        The measured features' standard errors.

    Returns
    -------
    dict
        Feature -> ``measured``, ``simulated`` (the mean), ``spread`` (the standard
        deviation with the measurement's and the mesh's errors), ``z`` and ``agrees``.

    """
    rng = np.random.default_rng(seed)
    draws = posterior.samples[rng.choice(posterior.samples.shape[0], size=members)]
    rows = []
    for member, params in zip(draw_members(ensemble.nuisances, members, seed + 1), draws,
                              strict=True):
        law_params = dict(zip(LAWS[posterior.law], (float(v) for v in params), strict=True))
        try:
            row = ensemble.member_vector(posterior.law, law_params, member)
        except SlipwaveError:
            continue
        rows.append(row)
    simulated = np.array(rows)
    z = band_z(len(FEATURES))
    mean = simulated.mean(axis=0)
    model = np.zeros(len(FEATURES)) if posterior.model_error is None else posterior.model_error
    spread = np.sqrt(simulated.var(axis=0, ddof=1) + error**2 + model**2)
    return {name: {"measured": round(float(ensemble.observed[k]), 6),
                   "simulated": round(float(mean[k]), 6),
                   "spread": round(float(spread[k]), 6),
                   "z": round(float((ensemble.observed[k] - mean[k]) / spread[k]), 3),
                   "agrees": bool(abs(ensemble.observed[k] - mean[k]) <= z * spread[k])}
            for k, name in enumerate(FEATURES)}


def law_entry(posterior: Posterior, best_evidence: float, simulations: int,
              decisive: float) -> dict[str, Any]:
    """A law's posterior in plain types (``fit.json``'s ``laws``).

    Parameters
    ----------
    posterior
        The law's.
    best_evidence
        The highest log evidence of the test's laws.
    simulations
        Simulations its search ran.
    decisive
        The log Bayes factor beyond which a law is rejected.

    Returns
    -------
    dict
        ``law``, ``parameters`` (value: posterior median, low and high: its central
        95 % interval, units), ``log_evidence``, ``log_bayes_factor`` (this law's
        against the law of highest evidence, <= 0), ``rejected``, ``guesses``, ``simulations``,
        ``seconds``, ``mesh_error`` (each feature's error from the mesh the likelihood
        carried, or null).

    """
    summary = posterior.summary()
    factor = posterior.log_evidence - best_evidence
    return {"law": posterior.law,
            "parameters": {name: {key: round(value, 6) for key, value in entry.items()}
                           | {"units": UNITS[name]} for name, entry in summary.items()},
            "log_evidence": round(posterior.log_evidence, 3),
            "log_bayes_factor": round(factor, 3),
            "rejected": bool(-factor > decisive),
            "guesses": int(posterior.points.shape[0]),
            "simulations": simulations,
            "seconds": round(posterior.seconds, 2),
            "mesh_error": None if posterior.model_error is None else {
                name: round(float(value), 6)
                for name, value in zip(FEATURES, posterior.model_error, strict=True)}}


DECISIVE = float(np.log(100.0))
"""A law whose evidence is below the highest by a factor of 100 or more is rejected
(Jeffreys' "decisive")."""
INDECISIVE = float(np.log(np.sqrt(10.0)))
"""Laws whose evidence is within this factor of the highest (Jeffreys' "barely worth
mentioning", below sqrt(10)) are told apart by their posterior predictive
(:func:`choose_law`). Set at Jeffreys' bound after two cases: the default campaign's
hl025 (a run-in; Coulomb e^0.55 more probable, its predictive differing on the first
slip) and a calibration run-in whose own predictive differed at e^2.2 Coulomb's evidence
(Coulomb's agreed, with fs 25 % low): a right law's predictive fails in 5 % of tests by
design, which a substantial factor should outweigh."""


@dataclass
class TestFit:
    """Every law's posterior on a test, and what they were computed with.

    Attributes
    ----------
    posteriors
        By law, in :data:`~slipwave.fit.laws.LAWS`' order.
    simulations
        Simulations each law's search ran.
    ensemble
        The test's ensemble (its measured features, members and settings).
    fine
        The same members at twice the mesh (the mesh's error, the mesh check).
    error
        The measured features' standard errors.
    threshold
        The test's edge threshold.

    """

    __test__ = False  # not a pytest class

    posteriors: dict[str, Posterior]
    simulations: dict[str, int]
    ensemble: Ensemble
    fine: Ensemble
    error: np.ndarray
    threshold: float

    @property
    def best(self) -> Posterior:
        """The law of highest evidence.

        Returns
        -------
        Posterior
            Its posterior.

        """
        return max(self.posteriors.values(), key=lambda posterior: posterior.log_evidence)


@dataclass(frozen=True)
class Choice:
    """The law a test is described by, its posterior predictive, and why it was chosen.

    Attributes
    ----------
    posterior
        The chosen law's.
    predictive
        Its :func:`predictive_check`.
    reason
        One sentence: the highest evidence, or which laws' predictive differed first.

    """

    posterior: Posterior
    predictive: dict[str, dict[str, Any]]
    reason: str


def choose_law(fitted: TestFit, settings: FitSettings) -> Choice:
    """The law of highest evidence whose posterior predictive reproduces every feature.

    Laws are taken by their evidence, those whose evidence is within a factor of
    :data:`INDECISIVE` of the highest only; each one's posterior predictive is checked
    (:func:`predictive_check`) until one agrees on every feature. Where the evidence
    barely tells the laws apart, the check does: a law that fails it is not a
    description of the test (Gelman, Meng and Stern 1996, posterior predictive checks as
    model criticism). When none agrees, the law of highest evidence is chosen, and its
    check says where it fails.

    Parameters
    ----------
    fitted
        Every law's posterior.
    settings
        The fit's settings (the predictive's members and seed).

    Returns
    -------
    Choice
        The chosen law, its predictive and why.

    """
    ranked = sorted(fitted.posteriors.values(), key=lambda p: -p.log_evidence)
    best = ranked[0]
    failed: list[tuple[str, list[str]]] = []
    first: dict[str, dict[str, Any]] | None = None
    for posterior in ranked:
        if best.log_evidence - posterior.log_evidence > INDECISIVE:
            break
        predictive = predictive_check(fitted.ensemble, posterior, settings.predictive_members,
                                      settings.search.seed, fitted.error)
        first = first or predictive
        differs = [name for name, check in predictive.items() if not check["agrees"]]
        if not differs:
            if not failed:
                return Choice(posterior, predictive, "the highest evidence")
            return Choice(posterior, predictive, "; ".join(
                f"{law}'s posterior predictive differs on {', '.join(names)}"
                for law, names in failed) + " and the evidence barely tells them apart "
                f"(this law's log Bayes factor {posterior.log_evidence - best.log_evidence:.1f}"
                "): the highest evidence of the laws whose predictive agrees on every feature")
        failed.append((posterior.law, differs))
    assert first is not None  # the best law is always checked
    return Choice(best, first, "the highest evidence; no law's posterior predictive agrees "
                  "on every feature, of those the evidence barely tells from it")


def fit_laws(setup: TestSetup, measured: pd.DataFrame, settings: FitSettings, *,
             laws: Sequence[str] = tuple(LAWS),
             detection: DetectionSettings = DEFAULT_DETECTION,
             cache: SolverCache | None = None) -> TestFit:
    """Every law's posterior on a test (Coulomb first: the others search around it).

    Parameters
    ----------
    setup, measured, settings, laws, detection, cache
        As in :func:`fit_test`.

    Returns
    -------
    TestFit
        The posteriors.

    Raises
    ------
    SlipwaveError
        For an unknown law, or a law the solver follows nowhere.

    """
    unknown = [law for law in laws if law not in LAWS]
    if unknown:
        raise SlipwaveError(f"unknown friction law(s) {unknown}; known: {', '.join(LAWS)}")
    cache = cache or SolverCache()
    threshold = probe_threshold(setup, measured, elements=settings.elements,
                                detection=detection, cache=cache)
    members = draw_members(settings.nuisances, settings.members, settings.search.seed)
    ensemble, fine = (Ensemble(setup, measured, members, threshold=threshold,
                               elements=elements, detection=detection, cache=cache,
                               nuisances=settings.nuisances)
                      for elements in (settings.elements, 2 * settings.elements))
    error = measurement_error(ensemble.measured, ratio_error=settings.ratio_error,
                              time_error=settings.time_error)
    likelihood = SyntheticLikelihood(ensemble.observed, error)
    posteriors: dict[str, Posterior] = {}
    simulations: dict[str, int] = {}
    for law in sorted(laws, key=list(LAWS).index):
        before = ensemble.simulations + fine.simulations
        box = first_box(law, measured, posteriors.get("coulomb"))
        posteriors[law] = search_law(law, partial(ensemble.features, law),
                                     likelihood, box, settings.search,
                                     dc_per_excess=dc_per_excess(setup, settings.elements),
                                     model_error=partial(mesh_error, ensemble, fine, law))
        simulations[law] = ensemble.simulations + fine.simulations - before
    return TestFit(posteriors, simulations, ensemble, fine, error, threshold)


def fit_test(setup: TestSetup, measured: pd.DataFrame, settings: FitSettings, *,
             laws: Sequence[str] = tuple(LAWS),
             detection: DetectionSettings = DEFAULT_DETECTION,
             cache: SolverCache | None = None) -> dict[str, Any]:
    """Fit every law to a test and choose one by evidence and posterior predictive.

    Parameters
    ----------
    setup
        The test's configuration (:func:`slipwave.setup.read_test_setup`).
    measured
        Its events (:func:`~slipwave.fit.features.measured_events`).
    settings
        The fit's settings.
    laws
        The laws to fit (Coulomb first when fitted: the others start around it).
    detection
        The detection's settings (the measurement's).
    cache
        The solver's cache, shared by every simulation.

    Returns
    -------
    dict
        ``fit.json``'s content: ``test_id``, ``setup`` (every value with its source),
        ``elements``, ``detection``, ``load_calibration``, ``measured`` (slip counts),
        ``edge_threshold``, ``features`` (the measured ones), ``laws`` (each
        :func:`law_entry`), ``chosen`` (:func:`choose_law`), ``chosen_because`` (its
        reason), ``parameters`` (the law
        the test's simulation takes: its posterior medians, or where the solver does not
        follow them the draw :func:`simulated_law` finds), ``parameters_note`` (None, or
        why they are not the medians), ``settings`` (the ensemble's and the search's),
        ``predictive`` (:func:`predictive_check`) and
        ``mesh_check`` (:func:`mesh_check`, or null).

    Raises
    ------
    SlipwaveError
        For an unknown law, or a law the solver follows nowhere.

    """
    cache = cache or SolverCache()
    fitted = fit_laws(setup, measured, settings, laws=laws, detection=detection, cache=cache)
    choice = choose_law(fitted, settings)
    chosen, predictive = choice.posterior, choice.predictive
    ensemble = fitted.ensemble
    finer = mesh_check(fitted, chosen, settings) if settings.mesh_check else None
    simulated, simulated_note = simulated_law(setup, chosen, settings.elements, cache)
    return {"test_id": setup.test_id, "setup": setup.to_dict(),
            "elements": settings.elements, "detection": detection.to_dict(),
            "load_calibration": settings.nuisances.load_calibration,
            "measured": {"slips": len(measured),
                         "gross_slips": len(ensemble.measured.gross),
                         "min_drop_n": round(float(measured.attrs.get("min_drop", 0.0)), 6)},
            "edge_threshold": round(fitted.threshold, 4),
            "features": {name: round(float(value), 6)
                         for name, value in zip(FEATURES, ensemble.observed, strict=True)},
            "laws": {law: law_entry(posterior, fitted.best.log_evidence,
                                    fitted.simulations[law], DECISIVE)
                     for law, posterior in fitted.posteriors.items()},
            "chosen": chosen.law,
            "chosen_because": choice.reason,
            "parameters": simulated,
            "parameters_note": simulated_note,
            "settings": {"members": settings.members,
                         "predictive_members": settings.predictive_members,
                         "stiffness_error": settings.nuisances.stiffness_error,
                         "speed_error": settings.nuisances.speed_error,
                         "step_jitter": settings.nuisances.step_jitter,
                         "ratio_error": settings.ratio_error,
                         "time_error_s": settings.time_error,
                         **{key: getattr(settings.search, key) for key in (
                             "design", "refinements", "draw_temperature", "samples",
                             "seed")}},
            "predictive": predictive,
            "mesh_check": finer}


FOLLOWED_DRAWS = 20
"""Posterior draws that :func:`simulated_law` tries when the solver does not follow the
medians: at evenly spaced ranks of their distance to them, nearest first."""


def simulated_law(setup: TestSetup, posterior: Posterior, elements: int,
                  cache: SolverCache | None = None) -> tuple[dict[str, float], str | None]:
    """The parameters the test's simulation takes: the medians, or a draw the solver follows.

    The medians of a law's parameters, taken one by one, are a law the solver may not
    follow over the whole test (a high fs on a tall slab can leave a gross slip with no
    quasi-static equilibrium: the active set cycles where the contact lands back on the
    flat), even when most draws are followed. The test's simulation then takes the
    nearest to the medians (in the draws' standard deviations) of
    :data:`FOLLOWED_DRAWS` draws that the solver follows on the test's setup, and says
    so.

    Parameters
    ----------
    setup
        The test's.
    posterior
        The chosen law's.
    elements
        The mesh of the test's simulation (the fit's).
    cache
        The solver's cache.

    Returns
    -------
    tuple
        The parameters (name -> value), and None for the medians or else a sentence
        saying which law is simulated and why.

    Raises
    ------
    SlipwaveError
        If the solver follows neither the medians nor any of the
        :data:`FOLLOWED_DRAWS` draws.

    """
    summary = posterior.summary()
    medians = np.array([summary[name]["value"] for name in posterior.names])
    scale = posterior.samples.std(axis=0)
    scale[scale == 0.0] = 1.0
    distance = np.sum(((posterior.samples - medians) / scale) ** 2, axis=1)
    # a ladder of draws from the nearest outwards: where the solver fails, it fails
    # over a region, not at a point
    ranks = np.linspace(0, distance.size - 1, FOLLOWED_DRAWS).astype(int)
    ladder = posterior.samples[np.argsort(distance)[ranks]]
    failure = ""
    for k, values in enumerate([medians, *ladder]):
        params = {name: round(float(value), 6)
                  for name, value in zip(posterior.names, values, strict=True)}
        try:
            setup.simulate(law_of(posterior.law, params), elements, cache=cache)
        except SlipwaveError as err:
            # the solver's own words (where and why), without the setup's advice
            failure = failure or str(err.__cause__ or err)
            continue
        if k == 0:
            return params, None
        return params, (f"The solver does not follow the posterior medians over the whole "
                        f"test (it stops at {failure}); the test is simulated with the "
                        f"posterior draw nearest them that it follows (draw {k} of "
                        f"{FOLLOWED_DRAWS}, counted from the nearest outwards).")
    raise SlipwaveError(f"the solver follows neither the {posterior.law} law's posterior "
                        f"medians nor {FOLLOWED_DRAWS} draws around them: {failure}")


def mesh_check(fitted: TestFit, posterior: Posterior, settings: FitSettings
               ) -> dict[str, Any]:
    """The chosen law searched again at twice the mesh, about its posterior.

    The search's design alone (:func:`~slipwave.fit.law_search.search_law`, no
    refinements) over the posterior's range widened (:func:`~slipwave.fit.law_search.
    posterior_box`), on the fit's finer ensemble (the same members, the same
    measured features and edge threshold). A law with a length scale (slip-weakening's
    Dc) converges once its process zone spans a few elements; Coulomb's law with
    fs > fd and run-in have none, and their coefficients are the mesh-dependent limit
    (docs: "Mesh convergence").

    Parameters
    ----------
    fitted
        The test's fit (:func:`fit_laws`).
    posterior
        The chosen law's, on the fit's mesh.
    settings
        As in :func:`fit_test`.

    Returns
    -------
    dict
        ``elements``, ``law``, ``parameters`` (median and 95 % interval at
        ``elements``), ``change`` (each parameter's relative change of median),
        ``simulations``, ``seconds`` and ``process_zone_mm`` (the law's process zone at
        the posterior median; null for a law without a length).

    """
    ensemble = fitted.fine
    elements, setup = ensemble.elements, ensemble.setup
    before = ensemble.simulations
    local = dataclasses.replace(settings.search, refinements=0)
    law = posterior.law
    values = {name: entry["value"] for name, entry in posterior.summary().items()}
    finer = search_law(law, partial(ensemble.features, law),
                       SyntheticLikelihood(ensemble.observed, fitted.error),
                       posterior_box(posterior), local,
                       dc_per_excess=dc_per_excess(setup, elements))
    summary = finer.summary()
    zone = setup.process_zone(law_of(law, values))
    return {"elements": elements, "law": law,
            "parameters": {name: {key: round(value, 6) for key, value in entry.items()}
                           | {"units": UNITS[name]} for name, entry in summary.items()},
            "change": {name: round((summary[name]["value"] - value) / value, 6)
                       for name, value in values.items()},
            "simulations": ensemble.simulations - before, "seconds": round(finer.seconds, 2),
            "process_zone_mm": round(zone, 4) if zone > 0 else None}


"""An ensemble per guess: a law simulated K times over what the recording does not fix.

A stick-slip cycle under fs > fd is chaotic: which partial slips come before a gross
one, and so the cycle the law settles in, changes when a coefficient moves by 0.2 %
(``benchmarks/RESULTS.md``, issue 15). One deterministic run per guess therefore tells
little; K runs, each with what the recording leaves uncertain drawn afresh, give the
spread a law's features have, and the synthetic likelihood
(:mod:`slipwave.fit.likelihood`) weighs each feature by it. Each member draws
(:func:`draw_members`):

- the load cells' calibration: T and N each read (1 + g) times the true load, g of
  standard deviation ``load_calibration``; the simulation's normal load is the measured
  one over (1 + g_N);
- the machine's stiffness and the drive's speed, within their relative standard errors;
- the cycle's initial state: the actuator's travel per quasi-static step, drawn within
  ``step_jitter`` of :data:`~slipwave.defaults.TRAVEL_STEP_MM` (where each step lands on
  the drive, hence where each slip starts within its step);
- the sensors' noise: white noise of the measured levels (the detection's estimates)
  added to T, N, DG and DD before detection.

The same members are drawn for every guess (common random numbers): two guesses then
differ by the law alone, not by their draws.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from slipwave.defaults import TRAVEL_STEP_MM
from slipwave.errors import SlipwaveError
from slipwave.events.detect import DEFAULT_DETECTION, DetectionSettings, detect_events
from slipwave.fit.features import (
    FEATURES,
    SlipFeatures,
    feature_vector,
    simulated_recording,
    slip_features,
)
from slipwave.fit.laws import law_of
from slipwave.fit.likelihood import ModelError
from slipwave.setup import TestSetup
from slipwave.solver import SolverCache
from slipwave.solver.signals import SIGNAL_VARIABLES


@dataclass(frozen=True)
class Nuisances:
    """How uncertain what the recording does not fix is (relative, one standard deviation).

    Attributes
    ----------
    load_calibration
        Each load cell's calibration.
    stiffness_error
        The machine's stiffness.
    speed_error
        The drive's speed.
    step_jitter
        Half-width of the uniform draw of the travel step, relative.

    """

    load_calibration: float
    stiffness_error: float
    speed_error: float
    step_jitter: float


@dataclass(frozen=True)
class Member:
    """One member's draw of the nuisances.

    Attributes
    ----------
    t_gain, n_gain
        The T and N cells' calibration errors (read = (1 + gain) true).
    stiffness, speed, travel_step
        Factors on the measured stiffness and speed, and on the nominal travel step.
    seed
        The member's noise seed.

    """

    t_gain: float
    n_gain: float
    stiffness: float
    speed: float
    travel_step: float
    seed: int


def draw_members(nuisances: Nuisances, count: int, seed: int) -> list[Member]:
    """``count`` members' nuisances, drawn from ``seed``.

    Parameters
    ----------
    nuisances
        Their uncertainties.
    count
        Members.
    seed
        The draw's seed.

    Returns
    -------
    list of Member
        The draws.

    Examples
    --------
    >>> members = draw_members(Nuisances(0.005, 0.02, 0.002, 0.2), 3, seed=1)
    >>> len(members), all(0.8 <= m.travel_step <= 1.2 for m in members)
    (3, True)
    """
    rng = np.random.default_rng(seed)
    return [Member(t_gain=float(rng.normal(0.0, nuisances.load_calibration)),
                   n_gain=float(rng.normal(0.0, nuisances.load_calibration)),
                   stiffness=float(1.0 + rng.normal(0.0, nuisances.stiffness_error)),
                   speed=float(1.0 + rng.normal(0.0, nuisances.speed_error)),
                   travel_step=float(1.0 + rng.uniform(-1.0, 1.0) * nuisances.step_jitter),
                   seed=int(rng.integers(2**31)))
            for _ in range(count)]


class Ensemble:
    """A test's ensemble: its members, and the features of a law's simulations over them.

    Parameters
    ----------
    setup
        The test's setup (:func:`slipwave.setup.read_test_setup`).
    measured
        Its events (:func:`slipwave.fit.features.measured_events`).
    members
        The members' draws (:func:`draw_members`).
    threshold
        The edge-jump ratio that tells gross slips (one per test).
    elements
        Elements along the contact.
    nuisances
        What the members were drawn from (a predictive check draws more).
    detection
        The detection's settings (the measurement's).
    cache
        The solver's cache, shared by every simulation.

    Attributes
    ----------
    measured
        The measured slips (:class:`~slipwave.fit.features.SlipFeatures`).
    observed
        Their :func:`~slipwave.fit.features.feature_vector`.
    simulations
        Simulations run.

    """

    def __init__(self, setup: TestSetup, measured: pd.DataFrame, members: Sequence[Member], *,
                 threshold: float, elements: int,
                 nuisances: Nuisances,
                 detection: DetectionSettings = DEFAULT_DETECTION,
                 cache: SolverCache | None = None):
        self.setup, self.members, self.threshold = setup, list(members), threshold
        self.nuisances = nuisances
        self.elements, self.detection = elements, detection
        self.cache = cache or SolverCache()
        self.sizes = {"min_drop": float(measured.attrs.get("min_drop", 0.0)),
                      "duration": float(measured.attrs["duration"]),
                      "sample_rate": float(measured.attrs["sample_rate"])}
        attrs = measured.attrs
        noise = {channel: float(attrs.get(f"{channel}_noise", np.nan))
                 for channel in ("T", "DG", "DD")}
        noise["N"] = noise["T"]  # the cells are alike; detection estimates T's alone
        self.noise = {channel: value if np.isfinite(value) else 0.0
                      for channel, value in noise.items()}
        self.measured = slip_features(measured, gross_edge_ratio=threshold, **self.sizes)
        self.observed = feature_vector(self.measured)
        self.simulations = 0
        self._runs: dict[tuple[str, tuple[float, ...]], np.ndarray] = {}

    def member_slips(self, law: str, params: Mapping[str, float], member: Member
                     ) -> SlipFeatures:
        """One member's slips under a law.

        Parameters
        ----------
        law
            One of :data:`~slipwave.fit.laws.LAWS`.
        params
            Its parameters.
        member
            The member's draws.

        Returns
        -------
        SlipFeatures
            Detected as the measurement's, with the member's calibration and noise.

        Raises
        ------
        SlipwaveError
            Where the solver cannot follow the law.

        """
        setup = self.setup.scaled({"normal_load_n": 1.0 / (1.0 + member.n_gain),
                                   "machine_stiffness_n_mm": member.stiffness,
                                   "speed_mm_s": member.speed}, "an ensemble member's draw")
        simulation = setup.simulate(law_of(law, params), self.elements, cache=self.cache,
                                    travel_step=TRAVEL_STEP_MM * member.travel_step,
                                    variables=SIGNAL_VARIABLES)
        self.simulations += 1
        recording = simulated_recording(simulation, setup,
                                        sample_rate=self.sizes["sample_rate"])
        rng = np.random.default_rng(member.seed)
        for channel, gain in (("T", member.t_gain), ("N", member.n_gain), ("DG", 0.0),
                              ("DD", 0.0)):
            values = recording[channel].values * (1.0 + gain)
            values = values + rng.normal(0.0, self.noise[channel], values.shape)
            recording[channel] = recording[channel].copy(data=values)
        recording.attrs["test_id"] = self.setup.test_id
        events = detect_events(recording, **self.detection.keywords(
            min_drop=self.sizes["min_drop"], edge_convention="x_axis"))
        return slip_features(events, gross_edge_ratio=self.threshold, **self.sizes)

    def member_vector(self, law: str, params: Mapping[str, float], member: Member
                      ) -> np.ndarray:
        """One member's :func:`~slipwave.fit.features.feature_vector` under a law.

        Parameters
        ----------
        law, params, member
            As in :meth:`member_slips`.

        Returns
        -------
        numpy.ndarray
            The features.

        Raises
        ------
        SlipwaveError
            Where the solver cannot follow the law.

        """
        return feature_vector(self.member_slips(law, params, member))

    def features(self, law: str, params: Mapping[str, float]) -> np.ndarray:
        """The members' feature vectors under a law (cached by parameters).

        Parameters
        ----------
        law
            One of :data:`~slipwave.fit.laws.LAWS`.
        params
            Its parameters.

        Returns
        -------
        numpy.ndarray
            Shape (members, features); a member the solver could not follow is a row of
            NaN.

        """
        key = (law, tuple(round(float(value), 9) for value in params.values()))
        if key not in self._runs:
            rows = []
            for member in self.members:
                try:
                    rows.append(self.member_vector(law, params, member))
                except SlipwaveError:
                    rows.append(np.full(len(FEATURES), np.nan))
            self._runs[key] = np.array(rows)
        return self._runs[key]


def mesh_error(coarse: Ensemble, fine: Ensemble, law: str, params: Mapping[str, float]
               ) -> ModelError:
    """Each feature's error from the mesh at a guess: the fit's mesh against a finer one.

    The numerical uncertainty of a validation (ASME V&V 20-2009; Roache 1998): what the
    fit's mesh computes differs from what a finer one does, and a Coulomb law with
    fs > fd does not converge at all (docs: "Mesh convergence"), so a measurement made by
    a finer model or by a real slab differs from the fit's simulations by more than the
    ensemble's scatter. Both ensembles run the same members, and their paired
    differences' mean d, with its own sampling variance v (the members' scatter over
    their number), gives both parts of the error. Its size is sqrt(max(d^2 - v, 0)):
    a feature on which the meshes agree within the members' scatter has no error from
    the mesh. Its shift, which carries the fit's features to the finer mesh, is d shrunk
    by the same share, d max(1 - v / d^2, 0) (James and Stein's shrinkage): a
    difference within the scatter moves nothing.

    Parameters
    ----------
    coarse, fine
        The test's ensembles on the fit's mesh and on the finer one (the same members).
    law
        One of :data:`~slipwave.fit.laws.LAWS`.
    params
        Its parameters.

    Returns
    -------
    ModelError
        Per feature (:data:`~slipwave.fit.features.FEATURES`); zero where fewer than two
        members ran on both meshes.

    Raises
    ------
    ValueError
        If the two ensembles' members differ.

    """
    if coarse.members != fine.members:
        raise ValueError("a mesh error compares the same members on two meshes")
    differences = fine.features(law, params) - coarse.features(law, params)
    differences = differences[np.all(np.isfinite(differences), axis=1)]
    if differences.shape[0] < 2:
        return ModelError(np.zeros(len(FEATURES)), np.zeros(len(FEATURES)))
    mean = differences.mean(axis=0)
    scatter = differences.var(axis=0, ddof=1) / differences.shape[0]
    beyond = np.maximum(mean**2 - scatter, 0.0)
    shift = np.divide(beyond, mean, out=np.zeros_like(mean), where=mean != 0.0)
    return ModelError(shift, np.sqrt(beyond))

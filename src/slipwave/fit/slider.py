"""Rate-and-state friction fitted to spring-slider records: a synthetic likelihood over windows.

A record is cut into windows of a few slips each and every window is summarised by
:func:`slipwave.events.stick_slip.slider_window_features`; the record's statistic is
the mean of its n windows' features. At a guess of the law (a, b - a, log10 Dc,
mu0), the bench is simulated (:func:`slipwave.solver.spring_slider.simulate_spring_slider`)
for a spin-up window and K more, the record's white noise added to each (common
random numbers: the same draws at every guess), and the K windows' features give the
mean and covariance of one window's statistic. The record's statistic then has the
Gaussian synthetic log-likelihood (Wood 2010) log N(observed; mean,
Sigma (1/n + 1/K) + diag(s^2 / n + floor^2)), s the record's own windows' standard
deviations (the observed mean's standard error, measured: a deterministic law's windows
can vary far less than a record's), Sigma shrunk as the slab's ensembles' are
(:func:`slipwave.fit.likelihood.shrunk_covariance`); records add. The posterior is
the slab's search machinery (:mod:`slipwave.fit.search`): a Gaussian-process
surrogate of the log-likelihood over a Latin hypercube and points added where its
upper confidence bound is highest, then emcee on prior x exp(surrogate).
"""

from __future__ import annotations

import contextlib
import json
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import xarray as xr
from scipy.stats import multivariate_normal, qmc

from slipwave.defaults import SLIDER_CUTOFF, SLIDER_DEFAULTS, SLIDER_EVOLUTION
from slipwave.errors import SlipwaveError
from slipwave.events.stick_slip import (
    FEATURES,
    noise_floor,
    regime_of,
    slider_window_features,
)
from slipwave.fit.likelihood import shrunk_covariance
from slipwave.fit.search import central_intervals, upper_bound_search
from slipwave.solver.rate_state import RateState, steady_friction
from slipwave.solver.spring_slider import SpringSlider, simulate_spring_slider

PARAMETERS = ("a", "b_minus_a", "log10_dc", "mu0")
"""The search's coordinates: a, b - a, log10 of Dc in metres, mu0 (at v0 = 1 um/s)."""

SECOND_STATE_PARAMETERS = ("b2", "log10_dc2")
"""A two-state law's further coordinates: b2 and log10 of Dc2 in metres."""

PRIOR_BOX = np.array([[0.002, 0.05], [-0.01, 0.03], [-7.0, -4.5], [0.15, 0.6]])
"""The uniform prior's bounds, one row per parameter. a: the direct effect is positive in
every measurement, 0.002-0.05 from rocks to paper and polymers; b - a: velocity
strengthening (negative) to strongly weakening; Dc: 0.1 to 30 um, the size of the
contacts between asperities or paper fibres; mu0: paper on paper's friction, 0.15 to 0.6
(the Colas records' median levels lie at 0.29-0.51)."""

CUTOFF_PARAMETERS = ("log10_vc",)
"""A cut-off law's further coordinate: log10 of the cut-off speed vc in m/s."""

SECOND_STATE_BOX = np.array([[-0.02, 0.02], [-6.0, -3.0]])
"""A second state's bounds: b2 of either sign, as large as b (negative, it strengthens
the interface as it renews: Blanpied and Tullis 1986); Dc2 from 1 um, above the first
state's lengths that matter, to 1 mm, the longest slip of a Colas record."""

CUTOFF_BOX = np.array([[-4.5, 0.0]])
"""The cut-off speed's bounds: from 30 um/s, below the slowest drive (42 um/s), where
steady sliding would strengthen at every drive speed, to 1 m/s, above the fastest slips
of a Colas record (mm/s to cm/s), where the cut-off changes nothing (b's effect lowered by
at most 1 % at 1 cm/s)."""

REFERENCE_SCATTER = 0.08
"""The scatter of the reference friction from one record to the next (standard deviation
of F/N): the Colas records' median levels differ by more than any law's speed dependence
explains (0.51 at 168 N/m and 4300 um/s, 0.29 at 1002 N/m and the same speed), as the
state of a paper surface changes from run to run; 0.08 is the standard deviation of the
six fitted records' median levels (0.081), the held-out records not read. The law's
dynamics do not depend on mu0, so this widens mu0's interval and nothing else."""

FEATURE_FLOOR = np.array([REFERENCE_SCATTER, 0.002, 0.02, 0.01, 0.02])
"""The smallest standard error of each feature's statistic (:data:`FEATURES`; the
recurrence's in its logarithm): the level's is the records' scatter
(:data:`REFERENCE_SCATTER`), the others' what a feature that does not vary over the
windows still carries of the model's own roughness."""

SPIN_UP_WINDOWS = 1
"""Windows simulated and dropped before the members: the start's transient."""

EVALUATIONS_PER_SECOND = 200_000
"""The integrator's evaluations of the right-hand side a guess's simulation may use per
simulated second; past them the guess has no likelihood, as one whose integration fails.
Measured on 40 laws drawn from the prior, each on the six Colas benches: a median of
2,200, at most 120,000 for a simulation that finished, a million for the two that failed
after a minute each; without a budget one law of a search kept Radau crawling for more
than ten minutes."""


@dataclass(frozen=True)
class SliderRecord:
    """A spring-slider record and its bench, as the fit reads it.

    Attributes
    ----------
    name
        The record's name.
    stiffness, drive_speed, mass, normal_load
        The bench (N/m, m/s, kg, N).
    window
        The windows' length, s.
    observed
        The mean of the record's windows' features (:data:`FEATURES`, the recurrence
        in its logarithm).
    windows
        The number of windows n.
    spread
        The standard deviations of the record's windows' features.
    noise
        The record's white-noise standard deviation
        (:func:`slipwave.events.stick_slip.noise_floor`; added to the simulations).
    sample_rate
        The record's samples per second (the simulations are sampled alike).
    regime
        The record's regime (from its whole length).

    """

    name: str
    stiffness: float
    drive_speed: float
    mass: float
    normal_load: float
    window: float
    observed: tuple[float, ...]
    windows: int
    spread: tuple[float, ...]
    noise: float
    sample_rate: float
    regime: str

    @property
    def bench(self) -> SpringSlider:
        """The record's bench.

        Returns
        -------
        SpringSlider
            Its mass, stiffness, drive speed and normal load.
        """
        return SpringSlider(mass=self.mass, stiffness=self.stiffness,
                            drive_speed=self.drive_speed, normal_load=self.normal_load)


def _vector(features: Mapping[str, float]) -> np.ndarray:
    """The features as the likelihood's vector (the recurrence in its logarithm)."""
    values = np.array([features[name] for name in FEATURES])
    values[FEATURES.index("recurrence")] = np.log(values[FEATURES.index("recurrence")])
    return values


def window_vectors(time: np.ndarray, ratio: np.ndarray, bench: SpringSlider,
                   window: float) -> np.ndarray:
    """The feature vectors of a record's consecutive windows.

    Parameters
    ----------
    time, ratio
        The record.
    bench
        Its spring-slider.
    window
        The windows' length, s (a shorter end is left out).

    Returns
    -------
    numpy.ndarray
        Shape (windows, features).
    """
    step = float(time[1] - time[0])
    size = round(window / step)
    count = time.size // size
    if count < 1:
        raise SlipwaveError(f"a record of {time[-1] - time[0]:.3g} s holds no window of "
                            f"{window:.3g} s")
    return np.array([_vector(slider_window_features(
        time[i * size:(i + 1) * size], ratio[i * size:(i + 1) * size],
        stiffness=bench.stiffness, drive_speed=bench.drive_speed,
        normal_load=bench.normal_load, mass=bench.mass)) for i in range(count)])


def slider_record(name: str, record: xr.Dataset, *, stiffness: float, drive_speed: float,
                  mass: float, normal_load: float, window: float) -> SliderRecord:
    """A record read for the fit: its windows' mean features, its noise and regime.

    Parameters
    ----------
    name
        The record's name.
    record
        ``friction_ratio`` over ``time`` (:func:`slipwave.io.slider_record.read_slider_record`).
    stiffness, drive_speed, mass, normal_load
        The bench (N/m, m/s, kg, N).
    window
        The windows' length, s.

    Returns
    -------
    SliderRecord
        The record as the fit reads it.
    """
    bench = SpringSlider(mass=mass, stiffness=stiffness, drive_speed=drive_speed,
                         normal_load=normal_load)
    time, ratio = record.time.values, record.friction_ratio.values
    rate = 1.0 / float(time[1] - time[0])
    vectors = window_vectors(time, ratio, bench, window)
    whole = slider_window_features(time, ratio, stiffness=stiffness, drive_speed=drive_speed,
                                   normal_load=normal_load, mass=mass)
    return SliderRecord(name, stiffness, drive_speed, mass, normal_load, window,
                        tuple(vectors.mean(axis=0)), vectors.shape[0],
                        tuple(vectors.std(axis=0, ddof=1) if len(vectors) > 1
                              else np.zeros(vectors.shape[1])),
                        noise_floor(ratio, rate, stiffness=stiffness, mass=mass), rate,
                        regime_of(whole["stuck_share"]))


def parameters(states: int, cutoff: bool = False) -> tuple[str, ...]:
    """The search's coordinates for a law of one or two states, with or without a cut-off.

    Parameters
    ----------
    states
        State variables, 1 or 2.
    cutoff
        Whether the law has a cut-off speed.

    Returns
    -------
    tuple of str
        :data:`PARAMETERS`, then :data:`SECOND_STATE_PARAMETERS` with two states, then
        :data:`CUTOFF_PARAMETERS` with a cut-off.
    """
    return (PARAMETERS + (SECOND_STATE_PARAMETERS if states == 2 else ())
            + (CUTOFF_PARAMETERS if cutoff else ()))


def prior_box(states: int, cutoff: bool = False) -> np.ndarray:
    """The uniform prior's bounds for a law of one or two states, with or without a cut-off.

    Parameters
    ----------
    states
        State variables, 1 or 2.
    cutoff
        Whether the law has a cut-off speed.

    Returns
    -------
    numpy.ndarray
        One row (low, high) per coordinate of :func:`parameters`.
    """
    return np.vstack([PRIOR_BOX] + ([SECOND_STATE_BOX] if states == 2 else [])
                     + ([CUTOFF_BOX] if cutoff else []))


def law_shape(coordinates: int) -> tuple[int, bool]:
    """The states and the cut-off of a law from its number of coordinates.

    Parameters
    ----------
    coordinates
        The length of a point of the search (:func:`parameters`).

    Returns
    -------
    tuple
        (states, cutoff).

    Raises
    ------
    SlipwaveError
        For a number no law has.
    """
    for states in (1, 2):
        for cutoff in (False, True):
            if len(parameters(states, cutoff)) == coordinates:
                return states, cutoff
    raise SlipwaveError(f"no spring-slider law has {coordinates} coordinates")


def law_at(point: np.ndarray, evolution: str = SLIDER_EVOLUTION) -> RateState:
    """The law at a point of the search's coordinates (:func:`parameters`).

    Parameters
    ----------
    point
        (a, b - a, log10 Dc, mu0), then (b2, log10 Dc2) for a two-state law, then
        log10 vc for a law with a cut-off.
    evolution
        The state's evolution law, ``"aging"`` or ``"slip"``.

    Returns
    -------
    RateState
        The law there (v0 1 um/s).
    """
    states, cutoff = law_shape(len(point))
    a, excess, log_dc, mu0 = (float(value) for value in point[:4])
    second = {"b2": float(point[4]), "dc2": 10.0 ** float(point[5])} if states == 2 else {}
    speed = {"cutoff_speed": 10.0 ** float(point[-1])} if cutoff else {}
    return RateState(a=a, b=a + excess, dc=10.0**log_dc, mu0=mu0,
                     evolution=evolution, **second, **speed)  # type: ignore[arg-type]


def simulated_windows(record: SliderRecord, law: RateState, members: int, seed: int
                      ) -> np.ndarray:
    """The features of ``members`` simulated windows of a record's bench under a law.

    Parameters
    ----------
    record
        The record (its bench, window and noise).
    law
        The friction law.
    members
        Windows kept after :data:`SPIN_UP_WINDOWS`.
    seed
        The noise's seed.

    Returns
    -------
    numpy.ndarray
        Shape (members, features); NaN rows where the integration failed.
    """
    rate = record.sample_rate
    duration = (SPIN_UP_WINDOWS + members) * record.window
    start = float(steady_friction(law, record.drive_speed)) - 1e-3
    try:
        simulation = simulate_spring_slider(
            record.bench, law, duration=duration, sample_rate=rate, initial_ratio=start,
            max_evaluations=int(EVALUATIONS_PER_SECOND * duration))
    except SlipwaveError:
        return np.full((members, len(FEATURES)), np.nan)
    time = simulation.time.values
    ratio = simulation.friction_ratio.values
    ratio = ratio + np.random.default_rng(seed).normal(0.0, record.noise, ratio.size)
    size = round(record.window * rate)
    kept = slice(SPIN_UP_WINDOWS * size, (SPIN_UP_WINDOWS + members) * size)
    return window_vectors(time[kept], ratio[kept], record.bench, record.window)[:members]


def record_loglik(record: SliderRecord, members: np.ndarray) -> float:
    """The record's synthetic log-likelihood given its simulated windows.

    Parameters
    ----------
    record
        The record (its observed mean and number of windows).
    members
        Shape (K, features), from :func:`simulated_windows`.

    Returns
    -------
    float
        log N(observed; mean, Sigma (1/n + 1/K) + diag(s^2 / n + floor^2)); -inf with fewer
        than two finite members.
    """
    finite = members[np.all(np.isfinite(members), axis=1)]
    if finite.shape[0] < 2:
        return float("-inf")
    covariance = shrunk_covariance(finite) * (1.0 / record.windows + 1.0 / finite.shape[0])
    covariance += np.diag(np.asarray(record.spread) ** 2 / record.windows + FEATURE_FLOOR**2)
    return float(multivariate_normal.logpdf(np.asarray(record.observed),
                                            mean=finite.mean(axis=0), cov=covariance))


@dataclass(frozen=True)
class SliderFitSettings:
    """How the spring-slider fit searches.

    Attributes
    ----------
    states
        State variables of the law fitted, 1 or 2.
    members
        Simulated windows per record and guess (K).
    design
        Points of the first Latin hypercube, per parameter.
    acquisitions
        Points added where the surrogate's upper confidence bound is highest, per
        parameter.
    exploration
        The upper bound's multiple of the surrogate's standard deviation.
    samples
        Posterior samples kept.
    processes
        Worker processes for the guesses' simulations.
    seed
        The fit's seed.
    evolution
        The state's evolution law fitted.
    cutoff
        Whether the law fitted has a cut-off speed.

    """

    states: int = SLIDER_DEFAULTS["states"]
    members: int = SLIDER_DEFAULTS["members"]
    design: int = SLIDER_DEFAULTS["design"]
    acquisitions: int = SLIDER_DEFAULTS["acquisitions"]
    exploration: float = SLIDER_DEFAULTS["exploration"]
    samples: int = SLIDER_DEFAULTS["samples"]
    processes: int = 1
    seed: int = SLIDER_DEFAULTS["seed"]
    evolution: str = SLIDER_EVOLUTION
    cutoff: bool = SLIDER_CUTOFF


def loglik(records: Sequence[SliderRecord], point: np.ndarray, members: int,
           seed: int, evolution: str = SLIDER_EVOLUTION) -> float:
    """The records' summed synthetic log-likelihood at a point.

    Parameters
    ----------
    records
        The records fitted together.
    point
        The search's coordinates (:data:`PARAMETERS`).
    members
        Simulated windows per record.
    seed
        The noise's seed (the same at every point).
    evolution
        The state's evolution law.

    Returns
    -------
    float
        The sum over the records of :func:`record_loglik`.
    """
    law = law_at(point, evolution)
    return float(sum(record_loglik(record, simulated_windows(record, law, members, seed + i))
                     for i, record in enumerate(records)))


def _evaluate(records: Sequence[SliderRecord], points: np.ndarray, settings: SliderFitSettings,
              pool: ProcessPoolExecutor | None) -> np.ndarray:
    """Log-likelihoods at points, on the fit's pool of processes if it has one."""
    jobs = [(records, point, settings.members, settings.seed, settings.evolution)
            for point in points]
    if pool is None:
        return np.array([loglik(*job) for job in jobs])
    return np.array(list(pool.map(_loglik_job, jobs)))


def _loglik_job(job: tuple[Sequence[SliderRecord], np.ndarray, int, int, str]) -> float:
    """:func:`loglik` of one job (a picklable call for the process pool)."""
    return loglik(*job)


def _inside(points: np.ndarray) -> np.ndarray:
    """Whether points lie in the prior: its box, and b = a + (b - a) >= 0."""
    points = np.atleast_2d(points)
    box = prior_box(*law_shape(points.shape[1]))
    return (np.all((points >= box[:, 0]) & (points <= box[:, 1]), axis=1)
            & (points[:, 0] + points[:, 1] >= 0.0))


def _prior_draws(count: int, rng: np.random.Generator | int, states: int, cutoff: bool
                 ) -> np.ndarray:
    """``count`` Latin hypercube points of the box that lie in the prior (of 4 count drawn)."""
    box = prior_box(states, cutoff)
    sampler = qmc.LatinHypercube(d=box.shape[0], seed=rng)
    points = qmc.scale(sampler.random(4 * count), box[:, 0], box[:, 1])
    return points[_inside(points)][:count]


def rate_state_values(samples: np.ndarray) -> dict[str, np.ndarray]:
    """A one-state law's parameters from samples of :data:`PARAMETERS`.

    Parameters
    ----------
    samples
        Shape (samples, coordinates), the first four :data:`PARAMETERS`.

    Returns
    -------
    dict
        ``a``, ``b``, ``b_minus_a``, ``dc`` (m), ``mu0``: each sample's value.

    Examples
    --------
    >>> rate_state_values(np.array([[0.01, 0.02, -5.0, 0.5]]))["b"].round(3).tolist()
    [0.03]
    """
    return {"a": samples[:, 0], "b": samples[:, 0] + samples[:, 1],
            "b_minus_a": samples[:, 1], "dc": 10.0 ** samples[:, 2], "mu0": samples[:, 3]}


@dataclass(frozen=True)
class SliderPosterior:
    """A spring-slider fit's result.

    Attributes
    ----------
    samples
        Posterior samples, the search's coordinates (:func:`parameters`).
    points, logliks
        The guesses evaluated and their summed synthetic log-likelihoods.
    records
        The names of the records fitted.
    evolution
        The state's evolution law fitted.

    """

    samples: np.ndarray
    points: np.ndarray
    logliks: np.ndarray
    records: tuple[str, ...]
    evolution: str = SLIDER_EVOLUTION

    @property
    def states(self) -> int:
        """State variables of the law fitted, 1 or 2 (from the coordinates' number).

        Returns
        -------
        int
            1 or 2.
        """
        return law_shape(self.samples.shape[1])[0]

    @property
    def cutoff(self) -> bool:
        """Whether the law fitted has a cut-off speed (from the coordinates' number).

        Returns
        -------
        bool
            True with a cut-off.
        """
        return law_shape(self.samples.shape[1])[1]

    def interval(self, probability: float = 0.95) -> dict[str, tuple[float, float, float]]:
        """Each parameter's median and central interval (b and Dc in their own units).

        Parameters
        ----------
        probability
            The interval's probability.

        Returns
        -------
        dict
            ``a``, ``b``, ``dc`` (m), ``mu0``, ``b_minus_a``, ``b2`` and ``dc2`` (m) for a
            two-state law, ``cutoff_speed`` (m/s) for a law with a cut-off: (median, low,
            high).
        """
        values = rate_state_values(self.samples)
        if self.states == 2:
            values |= {"b2": self.samples[:, 4], "dc2": 10.0 ** self.samples[:, 5]}
        if self.cutoff:
            values |= {"cutoff_speed": 10.0 ** self.samples[:, -1]}
        return central_intervals(values, probability)


def fit_records(records: Sequence[SliderRecord], settings: SliderFitSettings,
                progress: Callable[[str], None] | None = None,
                start: np.ndarray | None = None) -> SliderPosterior:
    """The posterior of (a, b - a, log10 Dc, mu0[, b2, log10 Dc2][, log10 vc]) given records.

    Parameters
    ----------
    records
        The records.
    settings
        The search's settings.
    progress
        Called with a line after each round of guesses.
    start
        Guesses evaluated with the design (rows of the search's coordinates; those outside
        the prior are left out): a one-state fit's best guesses with an idle second state
        or cut-off (:func:`nested_start`), from which a wider law's search starts where the
        nested law already fits.

    Returns
    -------
    SliderPosterior
        The posterior samples and the guesses.
    """
    box = prior_box(settings.states, settings.cutoff)
    # one pool for the whole search: its workers import slipwave once
    with (ProcessPoolExecutor(settings.processes) if settings.processes > 1
          else contextlib.nullcontext()) as pool:
        samples, points, logliks = upper_bound_search(
            lambda points: _evaluate(records, points, settings, pool), box,
            lambda count, rng: _prior_draws(count, rng, settings.states, settings.cutoff),
            _inside, design=settings.design, acquisitions=settings.acquisitions,
            exploration=settings.exploration, samples=settings.samples, seed=settings.seed,
            start=start, progress=progress)
    return SliderPosterior(samples, points, logliks, tuple(r.name for r in records),
                           settings.evolution)


NESTED_START_GUESSES = 4
"""A one-state fit's best guesses a wider law's search starts from (:func:`nested_start`)."""


def nested_start(posterior: SliderPosterior, states: int = 2, cutoff: bool = False
                 ) -> np.ndarray:
    """A one-state fit's best guesses as guesses of a wider law that leave it as it was.

    A second state is idle with b2 = 0 (Dc2 then changes nothing; it is set to the middle
    of its prior); a cut-off at the top of its prior (1 m/s) lowers the state's effect by
    at most 1 % in the fastest slips. The wider search so starts at the likelihood the
    one-state fit reached rather than looking for that basin again in more dimensions.

    Parameters
    ----------
    posterior
        A one-state fit without a cut-off.
    states
        The wider law's state variables, 1 or 2.
    cutoff
        Whether the wider law has a cut-off speed.

    Returns
    -------
    numpy.ndarray
        Shape (:data:`NESTED_START_GUESSES`, coordinates of the wider law).

    Raises
    ------
    SlipwaveError
        If the fit is not a one-state fit without a cut-off, or the law is not wider.
    """
    if posterior.states != 1 or posterior.cutoff:
        raise SlipwaveError("a wider law's search starts from a one-state fit without a "
                            f"cut-off, not a {posterior.states}-state one"
                            + (" with a cut-off" if posterior.cutoff else ""))
    if states == 1 and not cutoff:
        raise SlipwaveError("the law to start is the one-state law itself: nothing to nest")
    finite = np.isfinite(posterior.logliks)
    best = posterior.points[finite][np.argsort(posterior.logliks[finite])[-NESTED_START_GUESSES:]]
    idle = ([0.0, SECOND_STATE_BOX[1].mean()] if states == 2 else []) + (
        [CUTOFF_BOX[0, 1]] if cutoff else [])
    return np.hstack([best, np.tile(idle, (best.shape[0], 1))])


def predict_record(record: SliderRecord, posterior: SliderPosterior, draws: int,
                   members: int, seed: int) -> dict[str, Any]:
    """The posterior predictive of a record the fit did not see.

    Parameters
    ----------
    record
        The record (its bench; its observed features are only compared, never used).
    posterior
        The fit.
    draws
        Posterior samples simulated.
    members
        Windows simulated per sample.
    seed
        The draws' and the noise's seed.

    Returns
    -------
    dict
        For ``drop`` and ``recurrence`` (s) and ``stuck_share``: the predictive's median
        and 95 % interval of one window's median, and the measured value; the predicted
        regime (the most frequent over the draws' windows) and the measured one.
    """
    rng = np.random.default_rng(seed)
    picks = posterior.samples[rng.choice(len(posterior.samples), draws, replace=False)]
    windows = np.vstack([simulated_windows(record, law_at(point, posterior.evolution),
                                           members, seed + i)
                         for i, point in enumerate(picks)])
    windows = windows[np.all(np.isfinite(windows), axis=1)]
    recurrence = FEATURES.index("recurrence")
    windows[:, recurrence] = np.exp(windows[:, recurrence])
    observed = np.asarray(record.observed, dtype=float).copy()
    observed[recurrence] = np.exp(observed[recurrence])
    out: dict[str, Any] = {"record": record.name}
    for name in ("drop", "recurrence", "stuck_share"):
        column = windows[:, FEATURES.index(name)]
        low, middle, high = np.percentile(column, [2.5, 50.0, 97.5])
        measured = float(observed[FEATURES.index(name)])
        out[name] = {"predicted": float(middle), "low": float(low), "high": float(high),
                     "measured": measured, "inside": bool(low <= measured <= high)}
    regimes = [regime_of(share) for share in windows[:, FEATURES.index("stuck_share")]]
    names, counts = np.unique(regimes, return_counts=True)
    out["regime"] = {"predicted": str(names[np.argmax(counts)]), "measured": record.regime,
                     "shares": {str(n): int(c) / len(regimes) for n, c in
                                zip(names, counts, strict=True)}}
    return out


def posterior_json(posterior: SliderPosterior, settings: SliderFitSettings,
                   seconds: float) -> str:
    """The fit's parameters, their intervals and its cost as JSON.

    Parameters
    ----------
    posterior
        The fit.
    settings
        Its settings.
    seconds
        The fit's wall time.

    Returns
    -------
    str
        Indented JSON.
    """
    return json.dumps({
        "records": list(posterior.records),
        "evolution": posterior.evolution,
        "parameters": {name: dict(zip(("median", "low", "high"), values, strict=True))
                       for name, values in posterior.interval().items()},
        "guesses": len(posterior.points),
        "best_loglik": float(np.max(posterior.logliks)),
        "settings": asdict(settings),
        "seconds": seconds,
    }, indent=2)


BENCH_ATTRIBUTES = ("record_id", "role", "stiffness_n_m", "drive_speed_m_s", "mass_kg",
                    "normal_load_n", "window_s")
"""The attributes a spring-slider record's netCDF carries (``slipwave slider-ingest``)."""


def record_of(dataset: xr.Dataset) -> SliderRecord:
    """The record as the fit reads it, from its netCDF (:data:`BENCH_ATTRIBUTES`).

    Parameters
    ----------
    dataset
        ``friction_ratio`` over ``time``, with the bench's attributes.

    Returns
    -------
    SliderRecord
        Its windows' features, noise and regime.
    """
    missing = [name for name in BENCH_ATTRIBUTES if name not in dataset.attrs]
    if missing:
        raise SlipwaveError(f"not a spring-slider record of 'slipwave slider-ingest': no "
                            f"{', '.join(missing)}")
    attrs = dataset.attrs
    return slider_record(str(attrs["record_id"]), dataset,
                         stiffness=float(attrs["stiffness_n_m"]),
                         drive_speed=float(attrs["drive_speed_m_s"]),
                         mass=float(attrs["mass_kg"]),
                         normal_load=float(attrs["normal_load_n"]),
                         window=float(attrs["window_s"]))


def posterior_dataset(posterior: SliderPosterior, settings: SliderFitSettings,
                      seconds: float) -> xr.Dataset:
    """The posterior's samples and the guesses as a Dataset.

    Parameters
    ----------
    posterior
        The fit.
    settings
        Its settings (attributes).
    seconds
        The fit's wall time.

    Returns
    -------
    xarray.Dataset
        ``samples`` (sample, parameter), ``guesses`` (guess, parameter) and ``loglik``
        (guess).
    """
    return xr.Dataset(
        {"samples": (("sample", "parameter"), posterior.samples,
                     {"long_name": "posterior samples of the search's coordinates"}),
         "guesses": (("guess", "parameter"), posterior.points,
                     {"long_name": "the guesses evaluated"}),
         "loglik": ("guess", posterior.logliks,
                    {"long_name": "summed synthetic log-likelihood of the fitted records"})},
        coords={"parameter": list(parameters(posterior.states, posterior.cutoff))},
        attrs={"title": "rate-and-state friction fitted to spring-slider records",
               "records": " ".join(posterior.records), "evolution": posterior.evolution,
               "seconds": seconds,
               # netCDF has no boolean attribute: a flag is kept as 0 or 1
               **{f"setting_{name}": int(value) if isinstance(value, bool) else value
                  for name, value in asdict(settings).items()}},
    )


def posterior_of(dataset: xr.Dataset) -> SliderPosterior:
    """The posterior back from :func:`posterior_dataset`'s Dataset.

    Parameters
    ----------
    dataset
        The fit's netCDF.

    Returns
    -------
    SliderPosterior
        Its samples, guesses and records.
    """
    return SliderPosterior(dataset["samples"].values, dataset["guesses"].values,
                           dataset["loglik"].values, tuple(str(dataset.attrs["records"]).split()),
                           str(dataset.attrs["evolution"]))

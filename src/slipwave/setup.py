"""A real test's configuration, read from its files: what its simulation needs.

The slab's geometry and material come from the recording's header (the card's
metadata lines, ``length_mm``, ``height_mm``...) or from the campaign table's columns
of the same names, the table winning; the normal load, the drive speed and the
machine's stiffness are measured on the recording itself (:func:`normal_load_plateau`,
:func:`drive`). Every value keeps where it came from. The bench's virtual tests build on
this module (:func:`slipwave.bench.setup_bench_test`); it imports nothing of them.
What can be neither read nor measured is an error that names the test and the column
to add to the campaign table.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr

from slipwave.defaults import MAX_SPIKE, TRAVEL_STEP_MM
from slipwave.errors import SlipwaveError, SolverError
from slipwave.solver import (
    Coulomb,
    LoadPath,
    Slab,
    SlipWeakening,
    SolverCache,
    simulate,
    simulation_memory,
)
from slipwave.validation import setup_value_problem

GEOMETRY = {
    "length_mm": "contact length L, mm",
    "height_mm": "slab height H, mm",
    "width_mm": "slab width w, mm",
    "youngs_modulus_mpa": "Young's modulus E of the slab, MPa",
    "poisson_ratio": "Poisson's ratio of the slab",
}
"""Header keys and campaign-table columns of the slab's geometry and material."""

EDGE_REFERENCES = ("frame", "flat")
"""What the edge sensors read against: the loading frame (elastic deflection only) or
the flat (the slip accumulates in them)."""


@dataclass(frozen=True)
class Setting:
    """A value and where it came from.

    Attributes
    ----------
    value
        The value, in the project's units.
    source
        ``"campaign table"``, ``"recording header"`` or how it was measured.

    """

    value: float
    source: str


@dataclass(frozen=True)
class TestSetup:
    """Everything a test's simulation takes from the test's files.

    Attributes
    ----------
    test_id
        The test.
    settings
        ``length_mm``, ``height_mm``, ``width_mm``, ``youngs_modulus_mpa``,
        ``poisson_ratio``, ``normal_load_n``, ``speed_mm_s``, ``machine_stiffness_n_mm``,
        ``duration_s``, ``loading_time_s``, each a :class:`Setting`.
    edge_reference
        What the edge sensors read against (:data:`EDGE_REFERENCES`), from the
        campaign table's ``edge_reference`` column.

    """

    __test__ = False  # not a pytest class

    test_id: str
    settings: Mapping[str, Setting]
    edge_reference: str

    def __getitem__(self, key: str) -> float:
        return self.settings[key].value

    def slab(self, elements: int) -> Slab:
        """The test's slab, meshed with ``elements`` along the contact.

        Parameters
        ----------
        elements
            Elements along the contact.

        Returns
        -------
        Slab
            Its geometry and material.

        Raises
        ------
        SlipwaveError
            Naming the test, when the geometry or material is not a slab's.

        """
        try:
            return Slab(length=self["length_mm"], height=self["height_mm"],
                        width=self["width_mm"], youngs_modulus=self["youngs_modulus_mpa"],
                        poisson_ratio=self["poisson_ratio"], elements=elements)
        except SlipwaveError as err:
            raise SlipwaveError(f"test {self.test_id!r}: {err}") from err

    def simulate(self, friction: Coulomb, elements: int, *,
                 cache: SolverCache | None = None,
                 profile: Callable[[np.ndarray], np.ndarray] | None = None,
                 travel_step: float = TRAVEL_STEP_MM,
                 variables: Collection[str] | None = None) -> xr.Dataset:
        """The test simulated: its slab and load path with ``friction``.

        Parameters
        ----------
        friction
            The friction law.
        elements
            Elements along the contact.
        cache
            The solver's cache (:func:`slipwave.solver.simulate`).
        profile
            The slab's initial gap (``Slab.profile``, e.g.
            :func:`slipwave.solver.slab.rounded_corners`); ``None``: flat.
        travel_step
            The actuator's travel per load step, mm (:meth:`load_path`).
        variables
            The simulation's variables to return (:func:`slipwave.solver.simulate`);
            ``None``: all.

        Returns
        -------
        xarray.Dataset
            :func:`slipwave.solver.simulate`'s steps.

        Raises
        ------
        SlipwaveError
            Naming the test and its setup, when the solver fails on it.

        """
        try:
            slab = dataclasses.replace(self.slab(elements), profile=profile)
            return simulate(slab, friction, self.load_path(travel_step), cache=cache,
                            variables=variables)
        except SolverError as err:
            settings = ", ".join(f"{key} {self[key]:.4g} ({self.settings[key].source})"
                                 for key in ("youngs_modulus_mpa", "normal_load_n",
                                             "height_mm", "machine_stiffness_n_mm"))
            raise SlipwaveError(
                f"test {self.test_id!r}: the solver failed at {err} with {friction} and "
                f"{elements} elements; a setup far from a compliant slab's does that: check "
                f"{settings}") from err

    def process_zone(self, friction: Coulomb) -> float:
        """The cohesive zone of a slip front under slip-weakening, mm (Palmer and Rice 1973).

        G* Dc / ((fs - fd) sigma), with G* = E / (2 (1 + nu) (1 - nu)) the slab's
        plane-strain shear modulus for a mode II front and sigma = N / (L w) the mean
        contact pressure: the length a mesh must resolve for the law's predictions not
        to depend on it (docs: "Mesh convergence").

        Parameters
        ----------
        friction
            The law; Coulomb's (no Dc) has no such length.

        Returns
        -------
        float
            The length, mm; 0 for a law without Dc.

        Examples
        --------
        >>> values = {"youngs_modulus_mpa": 7.0, "poisson_ratio": 0.48,
        ...           "normal_load_n": 85.0, "length_mm": 80.0, "width_mm": 10.0}
        >>> setup = TestSetup("demo", {k: Setting(v, "example") for k, v in values.items()},
        ...                   "frame")
        >>> round(setup.process_zone(SlipWeakening(fs=0.9, fd=0.6, dc=0.1)), 1)
        14.3
        """
        if not isinstance(friction, SlipWeakening):
            return 0.0
        nu = self["poisson_ratio"]
        shear = self["youngs_modulus_mpa"] / (2.0 * (1.0 + nu) * (1.0 - nu))
        pressure = self["normal_load_n"] / (self["length_mm"] * self["width_mm"])
        return shear * friction.dc / ((friction.fs - friction.dynamic) * pressure)

    def simulation_memory(self, elements: int, sample_rate: float) -> int:
        """Bytes a simulation of the test takes at its peak, estimated before it starts.

        :func:`slipwave.solver.simulation_memory` of its slab, load path and
        recording.

        Parameters
        ----------
        elements
            Elements along the contact.
        sample_rate
            Of the simulated recording, Hz.

        Returns
        -------
        int
            The estimate, bytes (the measured peak is below it).

        """
        return simulation_memory(self.slab(elements), self.load_path(),
                                 samples=self["duration_s"] * sample_rate)

    def load_path(self, travel_step: float = TRAVEL_STEP_MM) -> LoadPath:
        """The test's load path: N held, the flat driven through the machine's spring.

        Parameters
        ----------
        travel_step
            The actuator's travel per load step, mm.

        Returns
        -------
        LoadPath
            See :func:`driven_load_path`.

        """
        return driven_load_path(normal_load=self["normal_load_n"], speed=self["speed_mm_s"],
                                duration=self["duration_s"],
                                loading_time=self["loading_time_s"],
                                machine_stiffness=self["machine_stiffness_n_mm"],
                                travel_step=travel_step)

    def scaled(self, factors: Mapping[str, float], source: str) -> TestSetup:
        """The setup with some values multiplied, each now from ``source``.

        Parameters
        ----------
        factors
            Setting -> factor (e.g. ``{"normal_load_n": 1.01}``).
        source
            Where the new values come from.

        Returns
        -------
        TestSetup
            A copy; the others' values and sources kept.

        Examples
        --------
        >>> setup = TestSetup("t", {"normal_load_n": Setting(80.0, "given")}, "frame")
        >>> setup.scaled({"normal_load_n": 1.5}, "drawn").settings["normal_load_n"]
        Setting(value=120.0, source='drawn')
        """
        settings = dict(self.settings)
        for key, factor in factors.items():
            settings[key] = Setting(settings[key].value * factor, source)
        return dataclasses.replace(self, settings=settings)

    @classmethod
    def from_dict(cls, content: Mapping[str, Any]) -> TestSetup:
        """The setup of :meth:`to_dict` (a ``fit.json``'s ``setup``).

        Parameters
        ----------
        content
            ``test_id``, ``edge_reference`` and ``{key: {"value", "source"}}``.

        Returns
        -------
        TestSetup
            The same setup.

        """
        try:
            settings = {key: Setting(float(item["value"]), str(item["source"]))
                        for key, item in content.items()
                        if key not in ("test_id", "edge_reference")}
            return cls(str(content["test_id"]), settings, str(content["edge_reference"]))
        except (KeyError, TypeError, ValueError) as err:
            raise SlipwaveError(f"not a test setup: {err}") from err

    def to_dict(self) -> dict[str, Any]:
        """The setup in plain types, each value with its source.

        Returns
        -------
        dict
            ``test_id``, ``edge_reference`` and ``{key: {"value", "source"}}``.

        """
        return {"test_id": self.test_id, "edge_reference": self.edge_reference,
                **{key: {"value": round(s.value, 6), "source": s.source}
                   for key, s in self.settings.items()}}


def driven_load_path(*, normal_load: float, speed: float, duration: float,
                     loading_time: float, machine_stiffness: float,
                     travel_step: float = TRAVEL_STEP_MM) -> LoadPath:
    """A bench's load path: the normal load held, the actuator driven at ``speed``.

    The actuator's travel covers the tangential loading (``duration`` less
    ``loading_time``) and two steps more, so that the sampled signals reach the
    recording's end.

    Parameters
    ----------
    normal_load
        Held after the normal loading, N.
    speed
        The actuator's speed, mm/s.
    duration
        The recording's length, s.
    loading_time
        How long the normal loading takes, s.
    machine_stiffness
        The spring between the actuator and the flat, N/mm.
    travel_step
        The actuator's travel per load step, mm.

    Returns
    -------
    LoadPath
        Normal load held (``force``), then the actuator's travel.

    Examples
    --------
    >>> path = driven_load_path(normal_load=85.0, speed=0.05, duration=40.0,
    ...                         loading_time=10.0, machine_stiffness=40.0)
    >>> round(path.max_travel, 6), path.travel_step
    (1.56, 0.03)
    """
    travel = speed * (duration - loading_time) + 2 * travel_step
    return LoadPath(normal_load=normal_load, normal_control="force",
                    machine_stiffness=machine_stiffness, max_travel=travel,
                    travel_step=travel_step)


def _first_held(condition: np.ndarray) -> int:
    """The first sample from which ``condition`` holds for longer than a spike; -1 if none.

    A spike of up to :data:`~slipwave.defaults.MAX_SPIKE` samples is no start: one of
    the card's spikes of T during the normal loading, taken for the tangential loading's
    start, had the normal load read on its rise.
    """
    held = MAX_SPIKE + 1
    if condition.size < held:
        return -1
    runs = np.lib.stride_tricks.sliding_window_view(condition, held).all(axis=1)
    return int(np.argmax(runs)) if runs.any() else -1


def _tangential_window(recording: xr.Dataset) -> np.ndarray:
    """Samples after the normal loading: from where T stays above 5 % of its range."""
    T = recording["T"].values
    low, high = np.nanpercentile(T, [1, 99])
    start = max(_first_held(T - low > 0.05 * (high - low)), 0)
    return np.arange(start, T.size)


def normal_load_plateau(recording: xr.Dataset) -> float:
    """The normal load reached by the normal loading, N (compressive magnitude).

    The median of |N| over the second before the tangential loading starts (T
    above 5 % of its range, and staying there for longer than a spike).

    Parameters
    ----------
    recording
        From :func:`slipwave.io.read_acquisition`, with an N channel.

    Returns
    -------
    float
        The plateau, N.

    """
    if "N" not in recording:
        raise SlipwaveError(f"test {recording.attrs.get('test_id', '?')!r}: no N channel to "
                            "measure the normal load on; add the column normal_load_n")
    time = recording["time"].values
    start = int(_tangential_window(recording)[0])
    before = (time >= time[start] - 1.0) & (time < time[start])
    if not before.any():
        raise SlipwaveError(f"test {recording.attrs.get('test_id', '?')!r}: the tangential "
                            "loading starts with the recording: no normal-load plateau")
    plateau = float(np.nanmedian(np.abs(recording["N"].values[before])))
    if not plateau > 0:
        raise SlipwaveError(f"test {recording.attrs.get('test_id', '?')!r}: N reads {plateau:g} "
                            f"N over the second before T rises (t = {time[start]:.4g} s): no "
                            "normal load measured; check the N column, or give the column "
                            "normal_load_n")
    return plateau


def normal_loading_time(recording: xr.Dataset, plateau: float) -> float:
    """How long the normal loading took, s: until |N| first held 99 % of its plateau.

    Parameters
    ----------
    recording
        With an N channel.
    plateau
        The normal load reached (:func:`normal_load_plateau`), N.

    Returns
    -------
    float
        The time from the recording's start, s.

    """
    if "N" not in recording:
        raise SlipwaveError(f"test {recording.attrs.get('test_id', '?')!r}: no N channel to "
                            "time the normal loading on")
    time = recording["time"].values
    reached = _first_held(np.abs(recording["N"].values) >= 0.99 * plateau)
    if reached < 0:
        raise SlipwaveError(f"test {recording.attrs.get('test_id', '?')!r}: N never holds "
                            "its plateau: no normal loading to time")
    return float(time[reached] - time[0])


def drive(recording: xr.Dataset, *, stiffness: float | None = None) -> tuple[float, float]:
    """The drive's speed (mm/s) and the machine's stiffness (N/mm), from T and DT.

    The actuator at X = V t + X0 drives the flat through the machine's spring, so at
    every sample, stick or slip, T = k (X - DT): DT = V t - T / k + X0. A least-squares
    fit of DT on t and T over the tangential loading gives V and k at once (a slope of
    DT alone would miss V by the spring's growing stretch as T rises); with k given,
    of DT + T / k on t, V alone. Samples from where a sensor saturated (the ingest's
    ``saturated_from_index``) are left out.

    Parameters
    ----------
    recording
        With T and DT channels.
    stiffness
        The machine's stiffness when known, N/mm (then returned as it is).

    Returns
    -------
    tuple of float
        (speed, stiffness).

    Raises
    ------
    SlipwaveError
        Without a DT channel, or when T does not load the spring (no stiffness).

    """
    test_id = recording.attrs.get("test_id", "?")
    wanted = "speed_mm_s" if stiffness is not None else "speed_mm_s and machine_stiffness_n_mm"
    if "DT" not in recording:
        raise SlipwaveError(f"test {test_id!r}: no DT channel to measure the drive on; add "
                            f"the column(s) {wanted}")
    window = _tangential_window(recording)
    for channel in ("T", "DT"):
        clipped = int(recording[channel].attrs.get("saturated_from_index", -1))
        if clipped >= 0:
            window = window[window < clipped]
    if window.size < 10:
        raise SlipwaveError(f"test {test_id!r}: fewer than 10 samples of tangential loading "
                            f"before T or DT saturates: add the column(s) {wanted}")
    time = recording["time"].values[window]
    T = recording["T"].values[window]
    travel = recording["DT"].values[window]
    good = np.isfinite(T) & np.isfinite(travel)
    if stiffness is not None:
        design = np.column_stack([time[good], np.ones(int(good.sum()))])
        (speed, _), *_ = np.linalg.lstsq(design, travel[good] + T[good] / stiffness,
                                         rcond=None)
        if not (np.isfinite(speed) and speed > 0):
            raise SlipwaveError(f"test {test_id!r}: the drive does not advance (speed "
                                f"{speed:.3g} mm/s from DT and T); add the column speed_mm_s")
        return float(speed), float(stiffness)
    design = np.column_stack([time[good], T[good], np.ones(int(good.sum()))])
    (speed, compliance, _), rss, *_ = np.linalg.lstsq(design, travel[good], rcond=None)
    # the compliance's standard error: a spring must show, at three of them
    variance = float(rss[0]) / max(1, design.shape[0] - 3) if np.size(rss) else 0.0
    error = float(np.sqrt(variance * np.linalg.inv(design.T @ design)[1, 1]))
    if not -compliance > 3.0 * error:
        raise SlipwaveError(f"test {test_id!r}: DT does not give way as T rises (no machine "
                            "spring to measure); add the column machine_stiffness_n_mm")
    if not speed > 0:
        raise SlipwaveError(f"test {test_id!r}: the drive does not advance (speed {speed:.3g} "
                            "mm/s from DT and T); add the column speed_mm_s")
    return float(speed), float(-1.0 / compliance)


def read_test_setup(recording: xr.Dataset, cells: Mapping[str, Any]) -> TestSetup:
    """A test's configuration: header and campaign table, then what is measured.

    Parameters
    ----------
    recording
        The test's recording (:func:`slipwave.io.read_acquisition`).
    cells
        The test's row of the campaign table (column -> cell; empty cells ignored).
        Columns ``length_mm``, ``height_mm``, ``width_mm``, ``youngs_modulus_mpa``,
        ``poisson_ratio``, ``normal_load_n``, ``speed_mm_s``,
        ``machine_stiffness_n_mm`` override the header and the measurements;
        ``edge_reference`` is ``frame`` or ``flat``.

    Returns
    -------
    TestSetup
        Every setting with its source.

    Raises
    ------
    SlipwaveError
        Naming the test and the column to add, for what is neither in the files nor
        measurable; or a cell that is not a positive number.

    """
    test_id = str(cells.get("test_id") or recording.attrs.get("test_id", "?"))

    def given(key: str) -> Setting | None:
        cell = str(cells.get(key, "") or "").strip()
        if cell:
            problem = setup_value_problem(key, cell)
            if problem is not None:
                raise SlipwaveError(f"test {test_id!r}: campaign-table column {key}: {problem}")
            return Setting(float(cell), "campaign table")
        if key in recording.attrs:
            problem = setup_value_problem(key, recording.attrs[key])
            if problem is not None:
                source = recording.attrs.get("source", "the recording")
                raise SlipwaveError(f"test {test_id!r}: {source}'s header line {key}: "
                                    f"{problem}; correct it, or give the column {key} in "
                                    "the campaign table (it wins over the header)")
            return Setting(float(recording.attrs[key]), "recording header")
        return None

    settings: dict[str, Setting] = {}
    for key, meaning in GEOMETRY.items():
        found = given(key)
        if found is None:
            raise SlipwaveError(f"test {test_id!r}: the {meaning} is neither in the "
                                f"recording's header nor in the campaign table: add the "
                                f"column {key} to the campaign table")
        settings[key] = found
    normal = given("normal_load_n")
    if normal is None or normal.source == "recording header":
        # the load the test reached, not the header's nominal one
        normal = Setting(normal_load_plateau(recording),
                         "measured: median |N| over the second before T rises")
    settings["normal_load_n"] = normal
    # The drive's real speed, not the header's nominal one, and the machine's spring.
    speed, stiffness = given("speed_mm_s"), given("machine_stiffness_n_mm")
    if (speed is None or speed.source == "recording header" or stiffness is None):
        measured = drive(recording, stiffness=None if stiffness is None else stiffness.value)
        how = "measured: least squares of DT on t and T over the tangential loading"
        if speed is None or speed.source == "recording header":
            speed = Setting(measured[0], how)
        if stiffness is None:
            stiffness = Setting(measured[1], how)
    settings["speed_mm_s"] = speed
    settings["machine_stiffness_n_mm"] = stiffness
    time = recording["time"].values
    interval = float(np.median(np.diff(time))) if time.size > 1 else 0.0
    settings["duration_s"] = Setting(float(time[-1] - time[0]) + interval,
                                     "recording length (samples times interval)")
    if "N" in recording:
        settings["loading_time_s"] = Setting(normal_loading_time(recording, normal.value),
                                             "measured: |N| reaching 99 % of its plateau")
    else:  # the normal load given, no N to time its loading on: T's rise starts after it
        settings["loading_time_s"] = Setting(
            float(time[_tangential_window(recording)[0]] - time[0]),
            "no N channel: the time T starts to rise")
    reference = str(cells.get("edge_reference", "") or "").strip()
    if reference not in EDGE_REFERENCES:
        what = f"is {reference!r}" if reference else "is not given"
        raise SlipwaveError(f"test {test_id!r}: what the edge sensors read against {what}: "
                            "set the campaign-table column edge_reference to frame or flat")
    return TestSetup(test_id, settings, reference)

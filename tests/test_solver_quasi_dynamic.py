"""The quasi-dynamic contact: its slip rate, its Jacobian, its 1-node reduction, its fronts."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from slipwave.errors import SlipwaveError
from slipwave.solver import quasi_dynamic as qd
from slipwave.solver import quasi_dynamic_steps as steps
from slipwave.solver import stiff_steps
from slipwave.solver.fronts import field_conditions, front_waves, slip_intervals
from slipwave.solver.rate_state import RateState, slip_rate, state_part
from slipwave.solver.simulate import Coulomb, LoadPath, simulate
from slipwave.solver.slab import Slab
from slipwave.solver.spring_slider import SpringSlider, simulate_spring_slider
from slipwave.solver.zones import node_conditions, track_zones, zone_events

SLIDING = RateState(a=0.01, b=0.015, dc=1e-6, mu0=0.6)  # K_c 1500 N/m under 0.3 N
SLAB_LAW = RateState(a=0.01, b=0.015, dc=2e-6, mu0=0.9)


def test_the_slip_rate_balances_friction_and_damping() -> None:
    rng = np.random.default_rng(3)
    a, v0 = 0.01, 1e-3
    for _ in range(200):
        # down to a node about to open: its undamped rate would overflow a double
        tau, pressure = rng.uniform(-2, 2), 10 ** rng.uniform(-9, 0.5)
        psi, damping = rng.uniform(0.3, 1.0), 10 ** rng.uniform(-6, 0)
        v = steps.slip_speed(tau, pressure, psi, damping, a, v0)
        carried = pressure * a * math.asinh(abs(v) * math.exp(psi / a) / (2 * v0))
        assert np.isfinite(v) and np.sign(v) == np.sign(tau)
        assert carried + damping * abs(v) == pytest.approx(abs(tau), rel=1e-10)
    # without damping it is the law's inverse
    law = RateState(a=a, b=0.01, dc=1e-6, mu0=0.6, v0=v0)
    log_state = np.log(2.0)
    psi = float(state_part(law, log_state))
    for ratio in (0.3, 0.6, 0.7):
        assert steps.slip_speed(ratio, 1.0, psi, 0.0, a, v0) == pytest.approx(
            float(slip_rate(law, ratio, log_state)), rel=1e-12)


@pytest.mark.parametrize("law", [
    RateState(a=0.01, b=0.015, dc=2e-6, mu0=0.05),
    RateState(a=0.01, b=0.015, dc=2e-6, mu0=0.05, evolution="slip", b2=0.005, dc2=1e-5,
              cutoff_speed=1e-4),
], ids=["aging", "slip, two states, cut-off"])
@pytest.mark.parametrize("control", ["displacement", "force"])
def test_the_jacobian_is_the_right_hand_side_s(law: RateState, control: str) -> None:
    body = qd.slab_body(Slab(elements=40))
    n = body.nodes
    u, dy, closed = qd._approach(body, 7.6)
    flat = qd._flat_row(qd.Drive(76.0, 0.048, control), dy, body.width)
    stretch = qd._Stretch(qd._reduce(body, closed[:-3], flat),  # three nodes open
                          qd._law(law), (1.0, 1.0))
    rng = np.random.default_rng(1)
    # sheared, with states that make the nodes slip at every rate from 1e-5 to 10 mm/s
    count = 2 if law.dc2 else 1
    y = np.empty(n * (1 + count))
    y[::1 + count] = u[:n] - 0.02 + 1e-3 * rng.standard_normal(n)
    for m in range(count):
        y[1 + m::1 + count] = rng.uniform(-8, 2, n)
    speeds = np.abs(stretch.step_end(0.3, y)[1])
    packed, band = stretch.jacobian(0.3, y), stretch.band
    numeric = np.empty((y.size, y.size))
    for j in range(y.size):
        step = 1e-9 if j % (1 + count) == 0 else 1e-7 * max(1.0, abs(y[j]))
        e = np.zeros(y.size)
        e[j] = step
        numeric[:, j] = (stretch.rates(0.3, y + e) - stretch.rates(0.3, y - e)) / (2 * step)
    rows, columns = np.indices(numeric.shape)
    inside = np.abs(rows - columns) <= band
    analytic = np.zeros_like(numeric)
    analytic[inside] = packed[columns[inside], band + rows[inside] - columns[inside]]
    scale = np.abs(numeric).max(axis=1, keepdims=True) + 1e-300
    assert (np.abs(analytic - numeric)[inside] / np.broadcast_to(scale, numeric.shape)[inside]
            ).max() < 1e-5
    # what the band leaves out is the far coupling, small beside a node's own
    slips = np.arange(0, y.size, 1 + count)
    own = np.abs(numeric[slips, slips])
    left_out = np.where(inside, 0.0, np.abs(numeric))[slips].sum(axis=1)
    assert (left_out[own > 0] / own[own > 0]).max() < 0.1  # 0.07-0.08 measured
    assert speeds.min() < 1e-3 < 1.0 < speeds.max()


@pytest.mark.parametrize("band", [1, 3, 8])
def test_the_band_lu_solves_with_interchanges(band: int) -> None:
    # a banded matrix whose diagonal is small beside its neighbours: pivoting is needed
    rng = np.random.default_rng(band)
    size = 60
    dense = np.zeros((size, size))
    LU = np.zeros((size, 3 * band + 1))
    for j in range(size):
        for d in range(-band, band + 1):
            if 0 <= j + d < size:
                value = rng.standard_normal() * (1e-3 if d == 0 else 1.0)
                dense[j + d, j] = value
                LU[j, 2 * band + d] = value
    pivots = np.zeros(size, dtype=np.int64)
    stiff_steps._band_lu(LU, pivots, band)
    assert (pivots != np.arange(size)).any()
    b = rng.standard_normal(size)
    x = stiff_steps._band_solve(LU, pivots, band, b)
    assert np.allclose(x, np.linalg.solve(dense, b), rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize(("per", "node_band"), [(2, 0), (2, 3), (3, 2)])
def test_the_newton_matrix_with_each_nodes_states_eliminated(per: int, node_band: int
                                                             ) -> None:
    # a Jacobian of the contact's pattern (a node's states touch its own position and
    # states only; positions couple within a band of nodes), its I - c J solved whole
    rng = np.random.default_rng(10 * per + node_band)
    nodes, states = 12, per - 1
    band = node_band * per + states  # the entries' half-width jacobian() is given
    size = nodes * per
    J = np.zeros((size, size))
    for k in range(nodes):
        rows = range(k * per, (k + 1) * per)
        for j in range(max(0, k - node_band), min(nodes, k + node_band + 1)):
            for row in rows:
                if abs(row - j * per) <= band:
                    J[row, j * per] = rng.standard_normal()
        for row in rows:
            for m in range(states):
                J[row, k * per + 1 + m] = rng.standard_normal()
    # a state's own entry near 1 / c: its block nearly singular before the elimination
    c = 0.7
    J[1, 1] = 1.0 / c - 1e-3
    packed = np.zeros((size, 2 * band + 1))
    for row in range(size):
        for column in range(size):
            if abs(row - column) <= band:
                packed[column, band + row - column] = J[row, column]
    factors = stiff_steps.factors_for(size, band, per)
    stiff_steps._factorise(packed, c, band, per, factors)
    b = rng.standard_normal(size)
    x = stiff_steps._solve(factors, per, b)
    assert np.allclose(x, np.linalg.solve(np.eye(size) - c * J, b), rtol=1e-8, atol=1e-10)


def _spring_sliders(stiffness: float, damping: float, duration: float
                    ) -> tuple[np.ndarray, np.ndarray]:
    """T/N of the 1-node contact and of the spring-slider, from rest with theta 10 s.

    The contact's steps at a tolerance tighter than their default (1e-6): what is
    checked is the reduction, not the default steps' accuracy.
    """
    body = qd.spring_slider_body(stiffness=stiffness / 1000.0, normal_load=0.3,
                                 damping=damping / 1000.0)
    reduced = qd.simulate_quasi_dynamic(body, SLIDING, qd.Drive(0.3, 0.01),
                                        duration=duration, sample_rate=100.0,
                                        tolerance=1e-6)
    slider = simulate_spring_slider(SpringSlider(0.0, stiffness, 1e-5, 0.3, damping=damping),
                                    SLIDING, duration=duration, sample_rate=100.0,
                                    initial_ratio=0.0, initial_log_state=math.log(10.0))
    return (reduced["T"] / reduced["N"]).values, slider["friction_ratio"].values


def test_one_node_is_the_quasi_dynamic_spring_slider() -> None:
    # below K_c: stick-slip, the slips braked by the damping (1 N s/m)
    reduced, slider = _spring_sliders(1000.0, 1.0, 30.0)
    assert reduced.max() - reduced[1000:].min() > 0.09  # it sticks and slips
    assert reduced.max() == pytest.approx(slider.max(), abs=1e-5)
    assert reduced[1000:].min() == pytest.approx(slider[1000:].min(), abs=1e-5)
    slips = [np.flatnonzero(np.diff(series) < -0.01) for series in (reduced, slider)]
    assert len(slips[0]) == len(slips[1]) >= 3
    assert np.abs(slips[0] - slips[1]).max() <= 1  # the same samples, to one


def test_one_node_slides_steadily_above_the_critical_stiffness() -> None:
    reduced, slider = _spring_sliders(1e5, 0.0, 3.0)
    steady = 0.6 + (0.01 - 0.015) * math.log(10.0)  # at ten times v0
    assert reduced[-1] == pytest.approx(steady, abs=1e-6)
    assert np.abs(reduced - slider).max() < 1e-5


@pytest.mark.parametrize("control", ["displacement", "force"])
def test_the_pressing_is_the_quasi_static_solver_s(control: str) -> None:
    slab = Slab(elements=40)
    quasi_static = simulate(slab, Coulomb(fs=0.9),
                            LoadPath(normal_load=76.0, normal_friction=False,
                                     normal_control=control, max_tangential_load=1.0))
    pressed = quasi_static.isel(step=int(np.flatnonzero(
        quasi_static["phase"].values == "normal")[-1]))
    ds = qd.simulate_quasi_dynamic(qd.slab_body(slab), SLAB_LAW,
                                   qd.Drive(76.0, 0.048, control), duration=0.1,
                                   sample_rate=10.0)
    first = ds.isel(field_time=0)
    assert float(ds["N"][0]) == pytest.approx(76.0, rel=1e-10)
    assert np.allclose(first["p"], pressed["p"], rtol=1e-8, atol=1e-10)
    assert float(ds["approach"][0]) == pytest.approx(float(pressed["approach"]), rel=1e-8)


def _appearances(codes: np.ndarray, x: np.ndarray) -> pd.DataFrame:
    """The zones that appear, in order, with the step they appear at."""
    events = zone_events(track_zones(codes, x, min_size=2.0))
    return events[events["event"] == "appear"].reset_index(drop=True)


def test_slow_loading_gives_the_quasi_static_succession() -> None:
    # the bench's slab under a law that barely depends on the rate (a 0.002, b 0): its
    # fronts run at the drive's pace, and the quasi-static solver's Coulomb law at the
    # same friction must give the same zones in the same order at the same T/N
    slab, friction, drive = Slab(elements=40), 0.6, qd.Drive(76.0, 0.048)
    quasi_static = simulate(slab, Coulomb(fs=friction),
                            LoadPath(normal_load=76.0, normal_friction=False))
    sheared = quasi_static["phase"].values == "tangential"
    before = _appearances(node_conditions(quasi_static["state"].values[sheared],
                                          quasi_static["slip_direction"].values[sheared]),
                          slab.x)
    ratio_before = (quasi_static["T"] / quasi_static["N"]).values[sheared]
    law = RateState(a=0.002, b=0.0, dc=2e-6, mu0=friction)
    ds = qd.simulate_quasi_dynamic(qd.slab_body(slab), law, drive, duration=60.0,
                                   sample_rate=10.0, field_times=qd.record_times(60.0, 20.0))
    after = _appearances(field_conditions(ds, slip_speed=1e-3 * drive.drive_speed), slab.x)
    ratio_after = np.interp(ds["field_time"], ds["time"], ds["T"] / ds["N"])
    # stick, a slip zone at the right edge, the right edge opening, the left edge slipping
    assert list(zip(before["condition"], before["where"], strict=True)) == list(
        zip(after["condition"], after["where"], strict=True))
    assert len(after) == 4
    load_step = 2.0 / 76.0  # the quasi-static solver's T step over N
    for k in range(1, 4):
        assert ratio_after[after["step"][k]] == pytest.approx(
            ratio_before[before["step"][k]], abs=load_step)
    # gross sliding at the law's steady friction at the drive's speed
    assert float(ds["T"][-1] / ds["N"][-1]) == pytest.approx(
        friction + law.a * math.log(drive.drive_speed / 1e3 / law.v0), abs=1e-4)


def test_a_held_normal_load_stays_and_a_held_position_does_not() -> None:
    body = qd.slab_body(Slab(elements=40))
    held = {control: qd.simulate_quasi_dynamic(body, SLAB_LAW, qd.Drive(76.0, 0.048, control),
                                               duration=20.0, sample_rate=1.0)
            for control in ("force", "displacement")}
    assert np.allclose(held["force"]["N"], 76.0, rtol=1e-9)
    assert np.ptp(held["force"]["approach"].values) > 0
    assert float(held["displacement"]["N"][-1]) > 80.0  # the shear presses the slab on
    assert np.ptp(held["displacement"]["approach"].values) == 0


@pytest.fixture(scope="module")
def slab_run() -> xr.Dataset:
    """A 40-element slab driven into stick-slip."""
    return qd.simulate_quasi_dynamic(qd.slab_body(Slab(elements=40)), SLAB_LAW,
                                     qd.Drive(76.0, 0.048), duration=60.0, sample_rate=50.0,
                                     field_times=qd.record_times(60.0, 5.0))


def test_the_slab_sticks_then_slips_in_waves(slab_run: xr.Dataset) -> None:
    ratio = (slab_run["T"] / slab_run["N"]).values
    drops = np.flatnonzero(np.diff(ratio) < -0.005)
    assert drops.size >= 3
    assert slab_run["time"].values[drops[0]] > 20.0  # the stick comes first
    waves = front_waves(slab_run, min_extent=0.25)
    assert len(waves) >= 3
    first = waves.iloc[0]
    # each wave starts inside the contact and is carried by fronts of metres per second
    assert -40.0 < first["x_start"] < 40.0
    assert 100.0 < first["speed"] < 1e5
    assert set(waves["direction"]) <= {"left_to_right", "right_to_left"}
    # a drop of T/N comes with each wave
    times = slab_run["time"].values[drops]
    assert all(np.abs(times - t).min() < 0.1 for t in waves["t_start"])


def test_slipping_nodes_are_closed_and_fast(slab_run: xr.Dataset) -> None:
    intervals = slip_intervals(slab_run)
    assert (intervals["end"] > intervals["start"]).all()
    fields = slab_run.sel(field_time=slice(30.0, None))
    fast = np.abs(fields["slip_rate"].values) > slab_run.attrs["front_speed"]
    assert (fields["contact"].values[fast] == 1).all()
    assert (fields["p"].values[fields["contact"].values == 0] == 0).all()


def test_the_recorded_displacements_carry_the_recorded_stresses(slab_run: xr.Dataset) -> None:
    # the contact's forces are the slab's stiffness times its displacements, node by node
    body = qd.slab_body(Slab(elements=40))
    u = np.concatenate([slab_run["ux"].values, slab_run["uy"].values], axis=1)
    forces = u @ body.stiffness.T
    closed = slab_run["contact"].values == 1
    n = body.nodes
    q = forces[:, :n] / body.tributary
    p = forces[:, n:] / body.tributary
    scale = float(np.abs(slab_run["p"]).max())
    assert np.abs(q - slab_run["q"].values)[closed].max() < 1e-8 * scale
    assert np.abs(p - slab_run["p"].values)[closed].max() < 1e-8 * scale
    # a closed node sits on the flat: its normal displacement is the flat's approach less
    # its gap
    approach = np.interp(slab_run["field_time"], slab_run["time"], slab_run["approach"])
    on_flat = approach[:, None] - body.initial_gap[None, :]
    assert np.abs(slab_run["uy"].values - on_flat)[closed].max() < 1e-9


def test_the_fields_are_recorded_when_asked() -> None:
    body = qd.spring_slider_body(stiffness=1.0, normal_load=0.3, damping=1e-3)
    asked = np.array([0.0, 0.125, 0.7])
    ds = qd.simulate_quasi_dynamic(body, SLIDING, qd.Drive(0.3, 0.01), duration=1.0,
                                   sample_rate=10.0, field_times=asked)
    np.testing.assert_array_equal(ds["field_time"].values, asked)
    with pytest.raises(SlipwaveError, match=r"field times must increase within 0 to 1\.0 s"):
        qd.simulate_quasi_dynamic(body, SLIDING, qd.Drive(0.3, 0.01), duration=1.0,
                                  sample_rate=10.0, field_times=np.array([0.5, 1.5]))


def test_a_full_buffer_of_field_states_loses_no_field(monkeypatch: pytest.MonkeyPatch
                                                      ) -> None:
    # the compiled steps hold the states at the field times until the driver takes them;
    # a buffer of two fills within steps and between contact changes, and the fields
    # are those of the default buffer, every record taken
    body = qd.slab_body(Slab(elements=40))

    def run() -> xr.Dataset:
        return qd.simulate_quasi_dynamic(body, SLAB_LAW, qd.Drive(76.0, 0.048), duration=50.0,
                                         sample_rate=20.0, field_times=qd.record_times(50.0, 40.0))

    held = run()
    monkeypatch.setattr(qd, "_FIELD_BUFFER", 2)
    small = run()
    assert small.attrs["steps"] == held.attrs["steps"] and held.attrs["contact_changes"] > 0
    assert (small["contact"].values.sum(axis=1) > 0).all()  # every record taken
    for name in ("slip_rate", "log_state", "p", "q", "contact", "ux", "uy"):
        expected = held[name].values
        np.testing.assert_allclose(small[name].values, expected, rtol=1e-12,
                                   atol=1e-12 * np.abs(expected).max())


def test_the_stepper_keeps_the_error_its_last_step_passed_with(monkeypatch: pytest.MonkeyPatch
                                                               ) -> None:
    # Stepper.error: each entry's local error in units of its tolerance, whose RMS a step
    # passes at 1 or less (written at every step: never the zeros it starts with)
    advance = qd.stretch_steps.advance
    seen: list[np.ndarray] = []

    def watched(stepper: stiff_steps.Stepper, *rest: object) -> int:
        status = advance(stepper, *rest)
        if stepper.counts[stiff_steps.STEPS]:
            seen.append(stepper.error.copy())
        return status

    monkeypatch.setattr(qd.stretch_steps, "advance", watched)
    qd.simulate_quasi_dynamic(qd.slab_body(Slab(elements=40)), SLAB_LAW, qd.Drive(76.0, 0.048),
                              duration=50.0, sample_rate=20.0)
    norms = np.array([np.sqrt(np.mean(error**2)) for error in seen])
    assert len(seen) > 5 and (norms <= 1.0).all() and (norms > 0.0).all()


def _crossings(x: np.ndarray, nodes: np.ndarray, rises: np.ndarray, falls: np.ndarray
               ) -> xr.Dataset:
    """A made-up simulation with these slip intervals."""
    times = np.concatenate([rises, falls])
    return xr.Dataset(
        {"crossing_x": ("crossing", np.concatenate([x[nodes], x[nodes]])),
         "crossing_time": ("crossing", times),
         "crossing_rising": ("crossing", np.r_[np.ones(nodes.size), np.zeros(nodes.size)]),
         "contact": (("field_time", "x"), np.ones((2, x.size)))},
        coords={"x": x, "time": np.linspace(0, 10, 11), "field_time": [0.0, 5.0]})


def test_a_front_s_speed_direction_and_extent_are_read_off_its_crossings() -> None:
    x = np.linspace(-40, 40, 81)
    # a front from x = 10 to the left edge at 200 mm/s, the nodes slipping for 50 ms,
    # and a short wave to the right at 50 mm/s later on
    left = np.arange(50, -1, -1)
    right = np.arange(60, 71)
    nodes = np.concatenate([left, right])
    rises = np.concatenate([1.0 + (x[50] - x[left]) / 200.0, 6.0 + (x[right] - x[60]) / 50.0])
    waves = front_waves(_crossings(x, nodes, rises, rises + 0.05))
    assert len(waves) == 2
    first, second = waves.iloc[0], waves.iloc[1]
    assert (first["x_start"], first["x_end"], first["direction"]) == (10.0, -40.0,
                                                                      "right_to_left")
    assert first["speed"] == pytest.approx(200.0)
    assert first["extent"] == pytest.approx(50 / 80)
    assert first["kind"] == "partial"
    assert (second["direction"], second["speed"]) == ("left_to_right", pytest.approx(50.0))
    assert len(front_waves(_crossings(x, nodes, rises, rises + 0.05), min_extent=0.3)) == 1


def test_bad_drives_and_runs_are_refused() -> None:
    with pytest.raises(SlipwaveError, match="normal load, speed"):
        qd.Drive(normal_load=76.0, drive_speed=0.0)
    with pytest.raises(SlipwaveError, match="normal control"):
        qd.Drive(76.0, 0.048, "both")  # type: ignore[arg-type]
    with pytest.raises(SlipwaveError, match="density"):
        qd.shear_impedance(Slab(elements=40), density=0.0)
    with pytest.raises(SlipwaveError, match="must be > 0"):
        qd.simulate_quasi_dynamic(qd.spring_slider_body(stiffness=1.0, normal_load=0.3),
                                  SLIDING, qd.Drive(0.3, 0.01), duration=0.0, sample_rate=1.0)
    with pytest.raises(SlipwaveError, match="mass 0"):
        SpringSlider(0.03, 1000.0, 1e-5, 0.3, damping=1.0)


def test_the_shear_impedance_is_half_the_square_root_of_g_rho() -> None:
    slab = Slab(elements=40)
    shear_modulus = 7e6 / (2 * 1.48)  # Pa
    wave_speed = math.sqrt(shear_modulus / 1200.0)  # m/s, about 44
    impedance = shear_modulus / (2 * wave_speed)  # Pa s/m
    assert qd.shear_impedance(slab) == pytest.approx(impedance * 1e-6 / 1e3)  # MPa s/mm


def test_a_run_ends_between_two_field_records() -> None:
    # the last field record (0.5 s) before the end (0.95 s): the steps stop at the end
    body = qd.spring_slider_body(stiffness=1.0, normal_load=0.3, damping=1e-3)
    ds = qd.simulate_quasi_dynamic(body, SLIDING, qd.Drive(0.3, 0.01), duration=0.95,
                                   sample_rate=20.0, field_times=qd.record_times(0.95, 2.0))
    assert ds["field_time"].values.tolist() == [0.0, 0.5]
    assert float(ds["time"][-1]) == pytest.approx(0.95)
    assert np.isfinite(ds["T"].values).all()

"""The solver against closed-form results and the properties the model must have."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from slipwave.io import read_dataset, write_dataset
from slipwave.solver import Coulomb, LoadPath, Slab, SolverCache, describe_behaviour, simulate
from slipwave.solver.contact import OPEN, SLIP, STICK, Body, Control
from slipwave.solver.simulate import RESIDUAL_TOLERANCE
from slipwave.solver.slab import condense

CACHE = SolverCache()  # the slabs of this file, condensed once

E, NU, WIDTH, LOAD = 7.0, 0.48, 10.0, 76.0
E_STAR = E / (1 - NU**2)
P_LINE = LOAD / WIDTH  # N per mm of width
RADIUS = 34.0


def hertz_slab(**kw) -> Slab:
    return Slab(height=40.0, profile=lambda x: x**2 / (2 * RADIUS), **kw)


def half_width(mask: np.ndarray, x: np.ndarray) -> float:
    """Half-width of a central zone: its outer nodes plus half a spacing each side."""
    nodes = np.flatnonzero(mask)
    return float(x[nodes[-1]] - x[nodes[0]]) / 2 + float(x[1] - x[0]) / 2


def last_normal(ds: xr.Dataset) -> int:
    return int(np.flatnonzero(ds["phase"].values == "normal")[-1])


@pytest.fixture(scope="module")
def bench_case() -> xr.Dataset:
    return simulate(Slab(height=40.0), Coulomb(fs=1.0), LoadPath(), cache=CACHE)


def test_hertz_frictionless():
    ds = simulate(hertz_slab(), Coulomb(fs=0.0), LoadPath(normal_load=LOAD, normal_steps=4),
                  cache=CACHE)
    k = last_normal(ds)
    x = ds["x"].values
    a = np.sqrt(4 * P_LINE * RADIUS / (np.pi * E_STAR))
    a_model = half_width(ds["state"].values[k] != 0, x)
    element = x[1] - x[0]
    assert abs(a_model - a) <= max(1.5 * element, 0.03 * a)
    p0 = 2 * P_LINE / (np.pi * a)
    assert float(ds["p"].values[k].max()) == pytest.approx(p0, rel=0.03)
    assert float(ds["N"][k]) == pytest.approx(LOAD, rel=1e-10)


@pytest.mark.parametrize("ratio", [0.25, 0.5, 0.75])
def test_cattaneo_stick_zone(ratio):
    f = 0.5
    path = LoadPath(normal_load=LOAD, normal_steps=4, normal_control="force",
                    tangential_step=ratio * f * LOAD)
    ds = simulate(hertz_slab(), Coulomb(fs=f), path, cache=CACHE)
    x = ds["x"].values
    a = half_width(ds["state"].values[last_normal(ds)] != 0, x)
    k = int(np.flatnonzero(ds["phase"].values == "tangential")[0])
    Q, P = float(ds["T"][k]), float(ds["N"][k])
    assert Q / (f * P) == pytest.approx(ratio, rel=1e-9)
    c = half_width(ds["state"].values[k] == STICK, x)
    expected = a * np.sqrt(1 - Q / (f * P))
    assert abs(c - expected) <= 2 * (x[1] - x[0]) + 0.03 * expected


@pytest.mark.parametrize("control", ["displacement", "force"])
def test_statics_every_step(control):
    ds = simulate(Slab(height=40.0), Coulomb(fs=0.8, fd=0.7),
                  LoadPath(normal_control=control, max_travel=1.6), cache=CACHE)
    tributary = ds["tributary_length"]
    np.testing.assert_allclose((ds["p"] * tributary).sum("x") * WIDTH, ds["N"], rtol=1e-12)
    np.testing.assert_allclose((ds["q"] * tributary).sum("x") * WIDTH, ds["T"], rtol=1e-9,
                               atol=1e-9)
    if control == "force":
        tangential = ds["phase"] == "tangential"
        np.testing.assert_allclose(ds["N"].where(tangential, drop=True), LOAD, rtol=1e-10)
    # Open nodes carry nothing; contact nodes are not pulled.
    state = ds["state"].values
    scale = float(np.abs(ds["p"]).max())
    assert np.all(np.abs(ds["p"].values[state == 0]) <= 1e-12 * scale)
    assert np.all(ds["p"].values[state != 0] >= -1e-12 * scale)


@pytest.mark.parametrize("f", [0.3, 0.6, 1.0])
@pytest.mark.parametrize("control", ["displacement", "force"])
def test_gross_sliding_ratio_equals_f(f, control):
    ds = simulate(Slab(height=40.0), Coulomb(fs=f), LoadPath(normal_control=control), cache=CACHE)
    assert ds.attrs["gross_sliding"] == "reached"
    assert str(ds["wave"].values[-1]) == "gross"
    T, N = float(ds["T"][-1]), float(ds["N"][-1])
    assert abs(T / N - f) <= 2.0 / N  # within one increment of load
    contact = ds["state"].values[-1] != 0
    assert np.all(ds["state"].values[-1][contact] == SLIP)
    before = ds["T"].values[-2]
    assert before <= f * float(ds["N"][-2]) + 1e-9  # the step before could still stick


def test_mirror_symmetry_after_normal_loading():
    for f in (0.2, 1.0):
        ds = simulate(Slab(height=40.0), Coulomb(fs=f), LoadPath(normal_steps=5), cache=CACHE)
        k = last_normal(ds)
        state = ds["state"].values[k]
        np.testing.assert_array_equal(state, state[::-1])
        p, q = ds["p"].values[k], ds["q"].values[k]
        np.testing.assert_allclose(p, p[::-1], rtol=1e-8, atol=1e-12)
        np.testing.assert_allclose(q, -q[::-1], rtol=1e-8, atol=1e-10)
        assert float(ds["DG"][k]) == pytest.approx(-float(ds["DD"][k]), rel=1e-8)


@pytest.mark.parametrize("f", [0.2, 0.6, 2.0])
def test_proportional_normal_loading_one_or_ten_steps(f):
    # the normal loading alone (a cap below the first tangential step)
    one = simulate(Slab(height=40.0), Coulomb(fs=f), LoadPath(normal_steps=1,
                                                             max_tangential_load=1.0), cache=CACHE)
    ten = simulate(Slab(height=40.0), Coulomb(fs=f), LoadPath(normal_steps=10,
                                                             max_tangential_load=1.0), cache=CACHE)
    a, b = last_normal(one), last_normal(ten)
    np.testing.assert_array_equal(one["state"].values[a], ten["state"].values[b])
    np.testing.assert_allclose(one["p"].values[a], ten["p"].values[b], rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(one["q"].values[a], ten["q"].values[b], rtol=1e-8, atol=1e-10)


def test_zero_friction_is_the_frictionless_solution():
    slab = Slab(height=40.0)
    ds = simulate(slab, Coulomb(fs=0.0), LoadPath(), cache=CACHE)
    k = last_normal(ds)
    assert np.abs(ds["q"].values).max() <= 1e-12 * np.abs(ds["p"].values).max()
    # The frictionless solution, solved directly: every node free to slide.
    condensed = condense(slab, cache=CACHE)
    body = Body(condensed.stiffness, slab.initial_gap())
    n = body.n
    u, _, _ = body.solve_linear(np.full(n, SLIP, dtype=np.int8), np.zeros(n), np.zeros(n),
                                Control(dx=0.0, N=LOAD / WIDTH))
    pressure = (condensed.stiffness @ u)[n:] / slab.tributary_length
    np.testing.assert_allclose(ds["p"].values[k], pressure, rtol=1e-9)
    assert ds["wave"].values[-1] == "gross" and len(ds["step"]) == k + 2


def test_large_friction_sticks_during_normal_loading(bench_case):
    # Normal loading only (a load cap below the first step): at f = 5 the tangential
    # phase leaves the range where the discrete Coulomb problem has a solution.
    ds = simulate(Slab(height=40.0), Coulomb(fs=5.0),
                  LoadPath(normal_steps=5, max_tangential_load=1.0), cache=CACHE)
    normal = ds["phase"].values == "normal"
    assert normal.all()
    assert np.all(ds["state"].values[normal] == STICK)
    assert np.all(bench_case["state"].values[bench_case["phase"].values == "normal"] == STICK)


def test_small_friction_slips_at_the_edges():
    ds = simulate(Slab(height=40.0), Coulomb(fs=0.3), LoadPath(), cache=CACHE)
    normal = ds["state"].values[ds["phase"].values == "normal"][-1]
    direction = ds["slip_direction"].values[ds["phase"].values == "normal"][-1]
    left, right = int(np.argmin(normal == SLIP)), int(np.argmin(normal[::-1] == SLIP))
    assert left == right > 0  # symmetric edge zones, slipping outward
    assert np.all(direction[:left] < 0) and np.all(direction[normal.size - right:] > 0)


def test_mesh_convergence():
    coarse = simulate(Slab(height=40.0, elements=160), Coulomb(fs=1.0), LoadPath(), cache=CACHE)
    fine = simulate(Slab(height=40.0, elements=320), Coulomb(fs=1.0), LoadPath(), cache=CACHE)
    assert float(fine["T"][-1]) == pytest.approx(float(coarse["T"][-1]), rel=0.01)
    element = 80.0 / 160
    # Zone boundaries at equal T (the load steps are the same): the open zone's
    # edge and the right slip front, every 10 N.
    for T in np.arange(40.0, 80.0, 10.0):
        kc = int(np.flatnonzero(np.isclose(coarse["T"].values, T))[0])
        kf = int(np.flatnonzero(np.isclose(fine["T"].values, T))[0])
        for code in (0, 1):
            xc = coarse["x"].values[coarse["state"].values[kc] == code]
            xf = fine["x"].values[fine["state"].values[kf] == code]
            assert abs(xc.max() - xf.max()) <= 2 * element + 1e-9
            assert abs(xc.min() - xf.min()) <= 2 * element + 1e-9


@pytest.mark.parametrize("hl", [0.1, 0.5, 1.0, 1.5])
@pytest.mark.parametrize("f", [0.1, 0.5, 1.0, 1.4])
def test_residual_grid(hl, f):
    ds = simulate(Slab(height=80.0 * hl), Coulomb(fs=f), LoadPath(), cache=CACHE)
    assert float(ds["residual"].max()) < RESIDUAL_TOLERANCE
    assert ds.sizes["step"] > 5


def test_bench_configuration_opens_right_then_slips_inside(bench_case):
    """The bench's own loading (friction while pressing, normal displacement held).

    The normal loading's locked-in shear makes slip start inside the left half and
    sweep right (ZG) beside the right edge's zone, as documented in the README; the
    paper's frictionless approach gives ZD (tests/test_solver_behaviour.py).
    """
    behaviour = describe_behaviour(bench_case)
    assert behaviour.first_opening == "right" and behaviour.opens_right_first
    assert behaviour.paper_name == "ZG"
    assert behaviour.sequence[0] == "opening right"
    assert "slip zone from right edge sweeps right-to-left" in behaviour.sequence
    assert behaviour.sequence[-2:] == ("slip zones merge", "gross sliding")
    # unloading slip at the right edge before the opening: an event, not in the succession
    assert behaviour.events[0]["event"] == "unloading slip"
    # The left edge is the last to slip.
    state = bench_case["state"].values
    last_stuck = [k for k in range(state.shape[0]) if state[k, 0] == STICK][-1]
    assert state[last_stuck + 1, 0] == SLIP and str(bench_case["wave"].values[-1]) == "gross"


def test_stick_slip_cycles_with_partial_waves_first():
    ds = simulate(Slab(height=40.0), Coulomb(fs=1.0, fd=0.8),
                  LoadPath(normal_control="force", max_travel=3.5), cache=CACHE)
    wave = ds["wave"].values
    gross = np.flatnonzero(wave == "gross")
    assert gross.size >= 3
    assert np.any(wave[: gross[0]] == "partial")  # partial waves before the first gross one
    T, DG, DD = ds["T"].values, ds["DG"].values, ds["DD"].values
    drops = np.flatnonzero(np.diff(T) < -1.0) + 1
    assert drops.size >= 3
    tangential = ds["phase"].values == "tangential"
    rising = np.flatnonzero((np.diff(T) > 0) & tangential[1:] & (wave[1:] == "none")) + 1
    assert rising.size > 5
    # Each drop of T: both faces move back, the way the stuck steps never move them.
    assert np.all(np.diff(DG)[drops - 1] < 0) and np.all(np.diff(DD)[drops - 1] < 0)
    assert np.all(np.diff(DG)[rising - 1] > 0) and np.all(np.diff(DD)[rising - 1] > 0)
    assert set(np.unique(wave[drops])) <= {"gross", "partial"}


def test_equal_runs_have_equal_successions(bench_case):
    again = describe_behaviour(simulate(Slab(height=40.0), Coulomb(fs=1.0), LoadPath(),
                                        cache=CACHE))
    assert again.sequence == describe_behaviour(bench_case).sequence
    other = describe_behaviour(simulate(Slab(height=40.0), Coulomb(fs=0.3), LoadPath(),
                                        cache=CACHE))
    assert other.sequence != again.sequence


def test_dataset_content_and_round_trip(bench_case, tmp_path):
    ds = bench_case
    for name in ["state", "slip_direction", "p", "q", "gap", "slip", "T", "N", "DG", "DD",
                 "DT", "phase", "residual"]:
        assert name in ds
    assert ds["state"].dtype == np.int8 and ds["state"].dims == ("step", "x")
    assert ds["x"].attrs["units"] == "mm" and ds["p"].attrs["units"] == "MPa"
    assert ds.attrs["friction_fs"] == 1.0 and ds.attrs["slab_height"] == 40.0
    assert set(np.unique(ds["slip_direction"].values)) <= {-1, 0, 1}
    assert np.all(ds["gap"].values >= 0)
    back = read_dataset(write_dataset(ds, tmp_path / "sim.nc"))
    xr.testing.assert_equal(back, ds)


def direct_solve(K: np.ndarray, g0: np.ndarray, state: np.ndarray, mu: np.ndarray,
                 s_prev: np.ndarray, control: Control) -> tuple[np.ndarray, float, float]:
    """A zone state's linear problem written out in full and solved densely: u, dx, dy.

    Independent of the solver's kept inverse: one equation per displacement (r = 0
    open; the flat's position stuck; Q = mu P slipping; contact closed), and the
    flat's two.
    """
    n = g0.size
    A = np.zeros((2 * n + 2, 2 * n + 2))
    b = np.zeros(2 * n + 2)
    X, Y = 2 * n, 2 * n + 1  # the flat's dx, dy
    for i in range(n):
        if state[i] == OPEN:
            A[i, : 2 * n] = K[i]
            A[n + i, : 2 * n] = K[n + i]
            continue
        A[n + i, n + i], A[n + i, Y], b[n + i] = 1.0, -1.0, -g0[i]  # closed: uy - dy = -g0
        if state[i] == STICK:
            A[i, i], A[i, X], b[i] = 1.0, -1.0, s_prev[i]
        else:
            A[i, : 2 * n] = K[i] - mu[i] * K[n + i]
    if control.dx is None:
        A[X, : 2 * n], A[X, X], b[X] = K[:n].sum(axis=0), control.machine, control.T
    else:
        A[X, X], b[X] = 1.0, control.dx
    if control.dy is None:
        A[Y, : 2 * n], b[Y] = K[n:].sum(axis=0), control.N
    else:
        A[Y, Y], b[Y] = 1.0, control.dy
    x = np.linalg.solve(A, b)
    return x[: 2 * n], float(x[X]), float(x[Y])


@pytest.mark.parametrize("zones", [(0.0, 0.8, 0.2), (0.6, 0.1, 0.3)],
                         ids=["mostly stuck", "mostly open"])
@pytest.mark.parametrize("kind", ["T and approach", "travel and N", "T and N"])
def test_the_kept_inverse_solves_every_state_of_a_walk_as_a_direct_solve(zones, kind):
    """The solver keeps one inverse and updates it as nodes change zone (bordering,
    reduction, a row per new coefficient) or forms it afresh when cheaper: along a
    random walk of zone states, coefficients, previous positions and loads, every
    solve must be the full problem's direct solution (on a crowned slab, some nodes
    with initial gaps)."""
    slab = Slab(height=40.0, elements=20, profile=lambda x: 1e-4 * (x / 40.0) ** 2)
    condensed = condense(slab, cache=CACHE)
    n = slab.initial_gap().size
    rng = np.random.default_rng(11)
    state = rng.choice(np.array([OPEN, STICK, SLIP], dtype=np.int8), size=n, p=zones)
    mu = 0.7 * rng.choice([-1.0, 1.0], size=n)

    def control(scale):
        return {"T and approach": Control(T=3.0 * scale, dy=-0.01 * scale, machine=2.0),
                "travel and N": Control(dx=0.01 * scale, N=LOAD / WIDTH * scale),
                "T and N": Control(T=2.0 * scale, N=LOAD / WIDTH, machine=1.0)}[kind]

    body = Body(condensed.stiffness, slab.initial_gap())
    for k in range(40):
        state[rng.integers(n, size=2)] = rng.choice([OPEN, STICK, SLIP], size=2)
        state[n // 2] = STICK  # the flat held by at least one stuck node
        if k % 3 == 0:
            mu[rng.integers(n)] = rng.uniform(-0.9, 0.9)  # a slipping node's new coefficient
        s_prev, loads = rng.normal(0.0, 1e-3, n), control(1.0 + 0.1 * k)
        u, dx, dy, r = body.solve_state(state, mu, s_prev, loads)
        u_direct, dx_direct, dy_direct = direct_solve(condensed.stiffness, slab.initial_gap(),
                                                      state, mu, s_prev, loads)
        scale = np.max(np.abs(u_direct))
        np.testing.assert_allclose(u, u_direct, rtol=1e-9, atol=1e-11 * scale)
        np.testing.assert_allclose([dx, dy], [dx_direct, dy_direct], rtol=1e-9,
                                   atol=1e-11 * scale)
        np.testing.assert_allclose(r, condensed.stiffness @ u, rtol=1e-9,
                                   atol=1e-11 * np.max(np.abs(r)))
    work = body.work()
    # the walk was solved by updates of the kept inverse, not by factorisations
    assert work["added"] > 10 and work["removed"] > 10 and work["rows changed"] > 3
    assert work["rebuilds"] < work["added"] + work["removed"]


@pytest.mark.parametrize("zones", [(0.0, 0.8, 0.2), (0.6, 0.1, 0.3)],
                         ids=["mostly stuck", "mostly open"])
@pytest.mark.parametrize("control", [Control(T=3.0, dy=-0.01, machine=2.0),
                                     Control(dx=0.01, N=LOAD / WIDTH),
                                     Control(T=2.0, N=LOAD / WIDTH, machine=1.0)],
                         ids=["T and approach", "travel and N", "T and N"])
def test_the_slips_sensitivity_to_the_coefficients_is_their_derivative(zones, control):
    """Slip-weakening's Newton step stands on d(ds)/d(mu): it must be the derivative of
    the very solution, whatever is imposed on the flat."""
    slab = Slab(height=40.0, elements=20)
    condensed = condense(slab, cache=CACHE)
    body = Body(condensed.stiffness, slab.initial_gap())
    n = body.n
    rng = np.random.default_rng(5)
    state = rng.choice(np.array([OPEN, STICK, SLIP], dtype=np.int8), size=n, p=zones)
    state[n // 2] = STICK  # the flat held by at least one stuck node
    slipping = np.flatnonzero(state == SLIP)
    mu = np.where(state == SLIP, 0.6 * rng.choice([-1.0, 1.0], size=n), 0.0)
    s_prev = rng.normal(0.0, 1e-3, n)

    def slips(coefficients):
        u, dx, _ = body.solve_linear(state, coefficients, s_prev, control)
        return (u[:n] - dx - s_prev)[slipping], (body.K @ u)[n:]

    ds, pressure = slips(mu)
    sensitivity = body.slip_sensitivity(state, mu, control, pressure)
    step = 1e-6
    numeric = np.column_stack([(slips(mu + step * (np.arange(n) == i))[0] - ds) / step
                               for i in slipping])
    assert np.abs(numeric).max() > 1e-3  # the coefficients do move the slips
    np.testing.assert_allclose(sensitivity, numeric, atol=1e-6 * np.abs(numeric).max())

"""Solver plumbing: caching, errors, free holder, CLI, plot."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import xarray as xr

from slipwave.cache import DiskCache
from slipwave.cli import main
from slipwave.errors import SlipwaveError, SolverError
from slipwave.io import read_dataset
from slipwave.plot import plot_zones
from slipwave.solver import (
    Body,
    Coulomb,
    LoadPath,
    Slab,
    SlipWeakening,
    SolverCache,
    active_set,
    simulate,
)
from slipwave.solver import contact as contact_module
from slipwave.solver import slab as slab_module
from slipwave.solver.compiled import CALLEE_GROUPS
from slipwave.solver.simulate import SIMULATION_VARIABLES


def test_a_cache_condenses_a_geometry_once_and_a_store_keeps_it_across_caches(
        tmp_path, monkeypatch):
    built = []
    assemble = slab_module.assemble_condensed
    monkeypatch.setattr(slab_module, "assemble_condensed",
                        lambda slab: built.append(slab) or assemble(slab))
    slab = Slab(height=30.0, elements=40)
    cache = SolverCache(DiskCache(tmp_path))
    first = slab_module.condense(slab, cache=cache)
    assert len(list(tmp_path.glob("condensed-*.npz"))) == 1
    doubled = slab_module.condense(Slab(height=30.0, elements=40, youngs_modulus=14.0),
                                   cache=cache)
    assert len(built) == 1  # E scales the unit condensation: not rebuilt
    np.testing.assert_allclose(doubled.stiffness, 2 * first.stiffness)
    monkeypatch.setattr(slab_module, "assemble_condensed", lambda *a, **k: pytest.fail("rebuilt"))
    again = slab_module.condense(slab, cache=SolverCache(DiskCache(tmp_path)))  # another process
    np.testing.assert_array_equal(again.stiffness, first.stiffness)


def test_without_a_cache_nothing_is_kept(monkeypatch):
    built = []
    assemble = slab_module.assemble_condensed
    monkeypatch.setattr(slab_module, "assemble_condensed",
                        lambda slab: built.append(slab) or assemble(slab))
    for _ in range(2):
        slab_module.condense(Slab(height=30.0, elements=20))
    assert len(built) == 2


def test_a_cache_keeps_the_frictionless_approach_and_gives_the_same_results():
    slab, path = Slab(height=40.0, elements=24), LoadPath(normal_steps=6, normal_friction=False)
    cache = SolverCache()
    first = simulate(slab, Coulomb(fs=0.8, fd=0.6), path, cache=cache)
    pressed = []
    solve = Body.solve_increment

    def counted(body, control, *args, **kwargs):
        if control.dx == 0.0:  # the flat pressed, not yet driven
            pressed.append(control.N)
        return solve(body, control, *args, **kwargs)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(Body, "solve_increment", counted)
        kept = simulate(slab, Coulomb(fs=0.8, fd=0.6), path, cache=cache)
        assert pressed == []  # the kept approach: the flat is not pressed again
        afresh = simulate(slab, Coulomb(fs=0.8, fd=0.6), path)
        assert len(pressed) >= path.normal_steps
    for name in ("T", "N", "DG", "DD", "state", "q"):
        np.testing.assert_array_equal(kept[name].values, first[name].values)
        np.testing.assert_array_equal(afresh[name].values, first[name].values)


def test_a_kept_body_restarted_gives_what_a_new_one_does():
    # the kept body's inverse is left as the last run left it: every simulation after
    # the first must still equal one made with a body of its own, to the bit
    slab = Slab(height=40.0, elements=24)
    runs = [(Coulomb(fs=0.9, fd=0.6), LoadPath(max_travel=1.0)),
            (SlipWeakening(fs=1.0, fd=0.7, dc=0.05), LoadPath(max_travel=1.0)),
            (Coulomb(fs=0.5), LoadPath(normal_control="force")),
            (Coulomb(fs=0.9, fd=0.6), LoadPath(max_travel=1.0))]
    cache = SolverCache()
    made = []
    original = Body.__init__

    def counted(body, *args, **kwargs):
        made.append(body)
        original(body, *args, **kwargs)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(Body, "__init__", counted)
        kept = [simulate(slab, law, path, cache=cache) for law, path in runs]
        assert len(made) == 1
        curved = dataclasses.replace(slab, profile=lambda x: 1e-3 * (x / 10.0) ** 2)
        kept.append(simulate(curved, Coulomb(fs=0.5), LoadPath(), cache=cache))
        assert len(made) == 2  # another gap, another body
    runs.append((Coulomb(fs=0.5), LoadPath()))
    for k, ((law, path), ds) in enumerate(zip(runs, kept, strict=True)):
        afresh = simulate(curved if k == len(runs) - 1 else slab, law, path)
        for name in ("T", "N", "DG", "DD", "state", "q", "p", "slip", "iterations"):
            np.testing.assert_array_equal(ds[name].values, afresh[name].values)


@pytest.mark.parametrize("wanted", [("T", "N"), ("DG_before_wave", "gap", "p"),
                                    ("state", "cascade_round", "actuator", "wave")])
def test_a_simulation_keeps_the_variables_asked_as_the_whole_result_has_them(wanted):
    slab = Slab(height=40.0, elements=24)
    path = LoadPath(max_travel=0.5)
    whole = simulate(slab, Coulomb(fs=0.9, fd=0.6), path)
    assert tuple(whole.data_vars) == SIMULATION_VARIABLES
    some = simulate(slab, Coulomb(fs=0.9, fd=0.6), path, variables=wanted)
    assert set(some.data_vars) == set(wanted)
    assert some.attrs == whole.attrs and set(some.coords) == set(whole.coords)
    for name in wanted:
        xr.testing.assert_identical(some[name], whole[name])


def test_an_unknown_variable_is_refused_before_simulating(monkeypatch):
    def fails(*args, **kwargs):
        raise AssertionError("simulated")

    monkeypatch.setattr(Body, "solve_increment", fails)
    with pytest.raises(ValueError, match="no variable pressure; it has state,"):
        simulate(Slab(elements=24), Coulomb(fs=0.5), variables=("T", "pressure"))


def test_damaged_store_file_is_rebuilt(tmp_path):
    store = DiskCache(tmp_path)
    slab = Slab(height=30.0, elements=20)
    key = slab_module.geometry_key(dataclasses.replace(slab, youngs_modulus=1.0, width=1.0))
    (tmp_path / f"condensed-{key}.npz").write_bytes(b"not an npz")
    assert store.load(key) is None
    condensed = slab_module.condense(slab, cache=SolverCache(store))
    np.testing.assert_allclose(store.load(key).stiffness, condensed.stiffness / 7.0, rtol=1e-12)


def test_truncated_store_file_is_rebuilt(tmp_path):
    store = DiskCache(tmp_path)
    slab = Slab(height=30.0, elements=20)
    condensed = slab_module.condense(slab, cache=SolverCache(store))
    (stored,) = tmp_path.glob("condensed-*.npz")
    stored.write_bytes(stored.read_bytes()[:200])
    again = slab_module.condense(slab, cache=SolverCache(store))
    np.testing.assert_array_equal(again.stiffness, condensed.stiffness)


def test_condensed_stiffness_is_symmetric_positive():
    condensed = slab_module.condense(Slab(height=40.0, elements=40))
    K = condensed.stiffness
    np.testing.assert_allclose(K, K.T, atol=1e-12 * np.abs(K).max())
    assert np.linalg.eigvalsh(K).min() > 0



@pytest.mark.parametrize("holder", ["clamped", "free"])
@pytest.mark.parametrize(("height", "elements"), [(12.0, 12), (40.0, 6)])
def test_condensation_equals_the_dense_schur_complement(holder, height, elements):
    """The substructured condensation is K_kk - K_ki K_ii^-1 K_ik, computed densely here
    (a wide slab is cut across its columns, a tall one across its rows)."""
    slab = Slab(height=height, length=16.0, elements=elements, holder=holder)
    assembly = slab_module._assemble(slab)
    assert set(np.unique(assembly.side)) == {-1, 0, 1}
    K = assembly.reduced.toarray()
    i, k = assembly.interior, assembly.kept
    dense = K[np.ix_(k, k)] - K[np.ix_(k, i)] @ np.linalg.solve(K[np.ix_(i, i)], K[np.ix_(i, k)])
    np.testing.assert_allclose(slab_module._schur_complement(assembly), dense,
                               rtol=0, atol=1e-12 * np.abs(dense).max())


@pytest.mark.parametrize(("columns", "rows"), [(1, 1), (7, 3), (161, 27), (20, 90)])
def test_nested_dissection_orders_every_node_once_with_each_separator_after_its_halves(
        columns, rows):
    order = slab_module.nested_dissection(columns, rows)
    assert np.array_equal(np.sort(order), np.arange(columns * rows))
    if columns * rows > 16:
        # the first cut is eliminated last: a whole line splitting the grid in two
        last = order[-min(columns, rows):]
        i, j = last % columns, last // columns
        assert np.unique(i).size == 1 or np.unique(j).size == 1

def test_non_converged_increment_raises_solver_error(monkeypatch):
    def never(*args, **kwargs):
        raise contact_module.NotConverged("test: no convergence")

    monkeypatch.setattr(contact_module.Body, "solve_increment", never)
    with pytest.raises(SolverError, match=r"^step 0: .*no convergence") as info:
        simulate(Slab(elements=40), Coulomb(fs=1.0), LoadPath())
    assert isinstance(info.value, SlipwaveError) and info.value.step == 0


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [({"height": 4.0}, "sensor height"), ({"poisson_ratio": 0.5}, "Poisson"),
     ({"elements": 2}, "at least 4"), ({"holder": "glued"}, "clamped")],
)
def test_bad_slab(kwargs, message):
    with pytest.raises(SlipwaveError, match=message):
        Slab(**kwargs)


def test_bad_friction():
    with pytest.raises(SlipwaveError, match="fd <= fs"):
        Coulomb(fs=0.5, fd=0.8)


def test_free_holder_jams_when_moment_needs_more_than_friction():
    # A holder free to rotate leaves the whole moment T*H to the contact: N >= T*2H/L,
    # so with f = 1 and H/L = 0.5 the slab cannot slide; the load cap ends the run.
    ds = simulate(Slab(height=40.0, elements=80, holder="free"), Coulomb(fs=1.0),
                  LoadPath(max_tangential_load=300.0))
    assert ds.attrs["gross_sliding"].startswith("not reached")
    assert float(ds["T"][-1]) == pytest.approx(300.0)
    assert np.all(ds["T"].values <= ds["N"].values + 1e-9)
    # Holding N instead, a low slab (moment capacity N L/2 > f N H) does slide.
    low = simulate(Slab(height=16.0, elements=80, holder="free"), Coulomb(fs=1.0),
                   LoadPath(normal_control="force"))
    assert low.attrs["gross_sliding"] == "reached"
    assert float(low["T"][-1]) == pytest.approx(76.0)


def test_cli_simulate(tmp_path, capsys):
    out = tmp_path / "sim.nc"
    png = tmp_path / "zones.png"
    code = main(["simulate", "--height", "40", "--fs", "1.0", "--fd", "0.9", "--elements", "40",
                 "-o", str(out), "--plot", str(png)])
    assert code == 0
    ds = read_dataset(out)
    assert ds.attrs["friction_fd"] == 0.9 and "behaviour" in ds.attrs
    assert png.stat().st_size > 1000
    assert "T/N at gross sliding 0.9000" in capsys.readouterr().out


def test_plot_zones_axes():
    ds = simulate(Slab(elements=40), Coulomb(fs=1.0), LoadPath())
    fig = plot_zones(ds)
    ax = fig.axes[0]
    assert ax.get_xlabel() == "x along the contact [mm]"
    assert ax.get_ylabel() == "tangential load T [N]"
    assert ax.get_xlim() == (-40.0, 40.0)


@pytest.mark.parametrize(("option", "message"), [
    (["--max-travel", "-5"], "max_travel must be positive, not -5"),
    (["--max-travel", "1", "--travel-step", "0"], "travel_step must be positive, not 0"),
])
def test_simulate_refuses_silly_travel(tmp_path, capsys, option, message):
    assert main(["simulate", "--fs", "1", "--elements", "8", "-o", str(tmp_path / "s.nc"),
                 *option]) == 1
    assert message in capsys.readouterr().err
    with pytest.raises(SlipwaveError, match=message):
        LoadPath(**{option[2 * k][2:].replace("-", "_"): float(option[2 * k + 1])
                    for k in range(len(option) // 2)})


@pytest.mark.parametrize("processes", ["1", "2", "8"])
def test_compile_reports_every_kernel_called_from_python(tmp_path, capsys, processes):
    import json

    out = tmp_path / "solver.json"
    assert main(["compile", "-o", str(out), "--processes", processes]) == 0
    report = json.loads(out.read_text())
    assert report["processes"] == min(int(processes), 2)
    assert {"iterate", "move_to", "set_base", "solve", "residual"} <= set(report["kernels"])
    # the kernels called from Python (their callees show only when compiled here)
    assert {"_despiked", "_best_hinge", "_line_at", "_finite_median", "_lowest_before_rise",
            "_level_falls"} <= set(report["detection"]["kernels"])
    for kernel in [*report["kernels"].values(), *report["detection"]["kernels"].values()]:
        assert kernel["loaded"] + kernel["compiled"] >= 1 and kernel["cache_path"]
    out = capsys.readouterr().out
    assert "solver: " in out and "detection: " in out


def test_the_callee_groups_share_out_every_callee_of_the_increment():
    body = active_set.zone_solver(np.eye(4), np.zeros(2))
    names = {name for name, _ in active_set.callee_examples(body, np.array([0.9, 0.6, 0.1]))}
    assert set().union(*CALLEE_GROUPS) == names
    assert not set(CALLEE_GROUPS[0]) & set(CALLEE_GROUPS[1])


_CALLEES_FIRST = """
import json, sys
from slipwave.solver.compiled import CALLEE_GROUPS, compile_callees, compile_solver
if sys.argv[1] == "callees":
    for group in CALLEE_GROUPS:
        compile_callees(group)
else:
    print(json.dumps(compile_solver()["kernels"]))
"""


@pytest.mark.slow
def test_callees_compiled_first_leave_the_increment_alone_to_compile(tmp_path):
    # Their example arguments must have the types the increment calls them with: a
    # callee it calls otherwise would be compiled again here, by the last process.
    import json
    import os
    import subprocess
    import sys

    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    for step in ("callees", "increment"):
        out = subprocess.run([sys.executable, "-c", _CALLEES_FIRST, step], env=env,
                             check=True, capture_output=True, text=True).stdout
    kernels = json.loads(out.strip().splitlines()[-1])
    assert {name for name, kernel in kernels.items() if kernel["compiled"]} == {"iterate"}
    assert kernels["move_to"]["loaded"] >= 1 and kernels["solve"]["loaded"] >= 1


@pytest.mark.parametrize("spread", [1e9, 1e11])
def test_an_ill_conditioned_state_is_not_inverted_afresh_at_every_solve(spread):
    """Refinement aims at what a fresh inverse reaches: no O(m^3) rebuild per solve."""
    rng = np.random.default_rng(3)
    n = 30
    basis, _ = np.linalg.qr(rng.normal(size=(2 * n, 2 * n)))
    stiffness = basis @ np.diag(np.logspace(0, np.log10(spread), 2 * n)) @ basis.T
    solver = active_set.zone_solver(0.5 * (stiffness + stiffness.T), np.zeros(n))
    state = np.full(n, active_set.STICK, dtype=np.int8)
    state[:25] = active_set.SLIP
    mu = np.where(state == active_set.SLIP, 0.5, 0.0)
    assert active_set.move_to(solver, state, mu)
    active_set.set_base(solver, np.zeros(n))
    u, r = np.empty(2 * n), np.empty(2 * n)
    rebuilds = []
    for dx in (0.01, 0.02, 0.03, 0.04):
        active_set.solve(solver, active_set.flat(dx, 0.0, None, None, np.inf), u, r)
        rebuilds.append(solver.counts[active_set.REBUILDS])
        slipping = np.flatnonzero(state == active_set.SLIP)
        equations = r[slipping] - 0.5 * r[n + slipping]
        assert np.abs(equations).max() <= 1e-11 * np.abs(r).max()
    assert rebuilds[-1] == rebuilds[0]  # the later solves refine, they do not rebuild
    # the well-conditioned state met REFINE_ABOVE; the other found what it can reach
    assert (solver.accuracy[0] > active_set.REFINE_ABOVE) == (spread > 1e10)


def test_a_singular_zone_state_is_refused_and_nothing_kept():
    # node 0 slipping frees its x displacement, whose equation K[0] - mu K[2] has no
    # entry on it when mu is 0: the bordering's pivot vanishes, and so does LAPACK's
    # (the rebuild), which says so (numba raises LinAlgError) rather than keep an
    # inverse of nothing
    stiffness = np.array([[0.0, 0.0, 0.5, 0.0], [0.0, 1.0, 0.0, 0.0],
                          [0.5, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
    solver = active_set.zone_solver(stiffness, np.zeros(2))
    state = np.array([active_set.SLIP, active_set.STICK], dtype=np.int8)
    assert not active_set.move_to(solver, state, np.array([0.0, 0.0]))
    assert solver.counts[0] == 0 and (solver.position == -1).all()
    # a regular state afterwards is taken: its inverse is 1 / (0 - 0.5 * 0.5)
    assert active_set.move_to(solver, state, np.array([0.5, 0.0]))
    assert solver.counts[0] == 1 and solver.inverse[0, 0] == pytest.approx(-4.0)

"""Solver plumbing: caching, errors, free holder, CLI, plot."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from slipwave.cache import DiskCache
from slipwave.cli import main
from slipwave.errors import SlipwaveError, SolverError
from slipwave.io import read_dataset
from slipwave.plot import plot_zones
from slipwave.solver import Coulomb, LoadPath, Slab, simulate
from slipwave.solver import contact as contact_module
from slipwave.solver import slab as slab_module


def test_condensed_matrices_cached_in_memory_and_in_a_store(tmp_path, monkeypatch):
    store = DiskCache(tmp_path)
    slab_module.forget_condensed()
    built = []
    assemble = slab_module.assemble_condensed
    monkeypatch.setattr(slab_module, "assemble_condensed",
                        lambda slab: built.append(slab) or assemble(slab))
    slab = Slab(height=30.0, elements=40)
    first = slab_module.condense(slab, store=store)
    assert len(list(tmp_path.glob("condensed-*.npz"))) == 1
    slab_module.condense(Slab(height=30.0, elements=40, youngs_modulus=14.0), store=store)
    assert len(built) == 1  # E does not rebuild
    slab_module.forget_condensed()
    monkeypatch.setattr(slab_module, "assemble_condensed", lambda *a, **k: pytest.fail("rebuilt"))
    again = slab_module.condense(slab, store=store)  # from the store, not rebuilt
    np.testing.assert_array_equal(again.stiffness, first.stiffness)
    doubled = slab_module.condense(Slab(height=30.0, elements=40, youngs_modulus=14.0))
    np.testing.assert_allclose(doubled.stiffness, 2 * first.stiffness)


def test_damaged_store_file_is_rebuilt(tmp_path):
    store = DiskCache(tmp_path)
    slab = Slab(height=30.0, elements=20)
    key = slab_module.geometry_key(dataclasses.replace(slab, youngs_modulus=1.0, width=1.0))
    (tmp_path / f"condensed-{key}.npz").write_bytes(b"not an npz")
    assert store.load(key) is None
    slab_module.forget_condensed()
    condensed = slab_module.condense(slab, store=store)
    np.testing.assert_allclose(store.load(key).stiffness, condensed.stiffness / 7.0, rtol=1e-12)


def test_condensed_stiffness_is_symmetric_positive():
    condensed = slab_module.condense(Slab(height=40.0, elements=40))
    K = condensed.stiffness
    np.testing.assert_allclose(K, K.T, atol=1e-12 * np.abs(K).max())
    assert np.linalg.eigvalsh(K).min() > 0


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

"""``load_drops`` on real recordings from another lab: Colas et al. (2019), paper on paper.

F/mg at 2 kHz from a spring-slider (see ../shared/data/colas2019/README.md;
CeCILL-B, J. Colas, N. Pustelnik, C. Oliver, P. Abry, J.-C. Geminard,
V. Vidal, Phys. Rev. E 2019). The data are read where they are, never copied.

The expected drops were checked by eye on plots of the records (onset
marked on the last sample of the ramp, end at the bottom of the fall):
every clear saw-tooth drop of the windows below, and nothing else there.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.io
from scipy.signal import find_peaks

from slipwave.events import despike, load_drops, noise_level

DATA = Path(__file__).parents[1].parent / "shared" / "data" / "colas2019"
pytestmark = pytest.mark.skipif(not DATA.is_dir(), reason=f"{DATA} is not there")

# K = 168 N/m, V = 42 um/s, 94-124 s: fifteen saw-tooth drops (onset s, drop F/mg)
SLOW_WINDOW = (94.0, 124.0)
SLOW_DROPS = [
    (95.382, 0.075), (98.870, 0.060), (100.734, 0.029), (103.272, 0.047), (105.011, 0.017),
    (105.832, 0.028), (108.610, 0.018), (110.252, 0.069), (112.572, 0.051), (114.197, 0.028),
    (116.162, 0.059), (118.289, 0.039), (120.464, 0.034), (122.262, 0.030), (123.521, 0.013),
]
# K = 168 N/m, V = 1100 um/s: the sharpest drops of 8.5-12.5 s (a linear rise, then a fall
# several times faster); the rounder, more symmetric cycles between them are left out
FAST_DROPS = [8.824, 9.4735, 9.695, 10.002, 10.150, 10.713, 10.828, 11.0645, 11.978]


def _record(name: str) -> tuple[np.ndarray, np.ndarray]:
    mat = scipy.io.loadmat(DATA / f"{name}.mat")
    return mat["t"].ravel(), mat["Fnorm"].ravel()


def test_slow_stick_slip_drops_agree_with_the_eye():
    time, force = _record("k168Nm_v42")
    drops = load_drops(time, force)
    inside = drops[drops["t_start"].between(*SLOW_WINDOW)]
    assert len(inside) == len(SLOW_DROPS)
    for (onset, size), (_, found) in zip(SLOW_DROPS, inside.iterrows(), strict=True):
        assert abs(found["t_start"] - onset) <= 0.005  # 10 samples
        assert found["drop"] == pytest.approx(size, abs=0.005)
        assert 0.005 < found["duration"] < 0.1
    # over the whole record, a saw-tooth: many drops, all faster than the ramps
    assert len(drops) > 200
    assert drops["duration"].median() < 0.05


def test_fast_stick_slip_drops_include_the_sharp_ones():
    time, force = _record("k168Nm_v1100")
    drops = load_drops(time, force)
    for onset in FAST_DROPS:
        assert np.abs(drops["t_start"].to_numpy() - onset).min() <= 0.01, onset
    assert 40 <= len(drops) <= 120  # about one drop per 0.2 s cycle over 14 s


def test_spikes_are_not_drops():
    """The slow record carries impulsive spikes of up to 0.02 F/mg, as tall as small drops."""
    time, force = _record("k168Nm_v42")
    part = force[(time >= 104.0) & (time < 106.0)]
    sigma = noise_level(force)
    outliers = np.abs(part - np.repeat(despike(part), 5))
    assert (outliers > 10 * sigma).sum() >= 10  # spikes are there
    drops = load_drops(time, force)
    assert drops["t_start"].between(104.0, 106.0).sum() == 2  # 105.01 and 105.83 only


@pytest.mark.parametrize("name", ["k168Nm_v4300", "k1002Nm_v4300", "k2254Nm_v4300"])
def test_inertial_oscillations_are_not_a_saw_tooth(name):
    time, force = _record(name)
    sigma = noise_level(force)
    cycles, _ = find_peaks(despike(force), prominence=8 * sigma)
    drops = load_drops(time, force)
    assert len(cycles) > 40
    assert len(drops) <= 0.05 * len(cycles), (len(drops), len(cycles))

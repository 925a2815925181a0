"""Spring-slider records in MAT files: read as they are, refused with the place of the fault."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.io

from slipwave.errors import AcquisitionError
from slipwave.io.slider_record import read_slider_record

DATA = Path(__file__).parents[1].parent / "shared" / "data" / "colas2019"


def _save(path: Path, **variables: object) -> Path:
    scipy.io.savemat(path, variables)
    return path


def test_a_record_is_read_as_saved(tmp_path: Path) -> None:
    time = 93.9095 + np.arange(500)[:, None] / 2000.0  # a column, as MATLAB saves it
    ratio = 0.3 + 0.01 * np.sin(np.arange(500))[:, None]
    ds = read_slider_record(_save(tmp_path / "k168Nm_v42.mat", t=time, Fnorm=ratio))
    np.testing.assert_array_equal(ds.friction_ratio, ratio.ravel())
    np.testing.assert_allclose(ds.time, time.ravel() - time[0, 0])
    assert ds.attrs["first_time_s"] == pytest.approx(93.9095)
    assert ds.attrs["sample_rate_hz"] == pytest.approx(2000.0)
    assert ds.friction_ratio.attrs["units"] == "1"


@pytest.mark.parametrize(("variables", "message"), [
    ({"t": np.arange(5.0)}, "no variable 'Fnorm'"),
    ({"t": np.arange(5.0), "Fnorm": np.ones((2, 5))}, "numeric vector"),
    ({"t": np.arange(5.0), "Fnorm": np.ones(4)}, "5 samples and 'Fnorm' 4"),
    ({"t": np.arange(5.0), "Fnorm": np.array([0.1, 0.2, np.nan, 0.3, 0.3])}, "sample 3"),
    ({"t": np.array([0.0, 1.0, 2.0, 2.5, 4.0]), "Fnorm": np.ones(5)}, "samples 3 and 4"),
])
def test_a_faulty_record_is_refused_with_its_place(
        tmp_path: Path, variables: dict[str, object], message: str) -> None:
    path = _save(tmp_path / "bad.mat", **variables)
    with pytest.raises(AcquisitionError, match=message) as caught:
        read_slider_record(path)
    assert str(path) in str(caught.value)


def test_a_file_that_is_no_mat_file_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "k1Nm_v1.mat"
    path.write_text("time,Fnorm\n0,0.3\n")
    with pytest.raises(AcquisitionError, match="not a readable MAT file"):
        read_slider_record(path)


@pytest.mark.skipif(not DATA.is_dir(), reason=f"{DATA} is not there")
def test_the_colas_records_are_read() -> None:
    ds = read_slider_record(DATA / "k2254Nm_v4300.mat")
    assert ds.sizes["time"] == 7521
    assert ds.attrs["sample_rate_hz"] == pytest.approx(2000.0)
    assert 0.3 < float(ds.friction_ratio.median()) < 0.4

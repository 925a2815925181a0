"""The spring-slider campaign table: read, checked line by line, turned into options."""

from __future__ import annotations

from pathlib import Path

import pytest

from slipwave.defaults import SLIDER_DEFAULTS
from slipwave.errors import ConfigError
from slipwave.slider_campaign import (
    read_slider_campaign,
    slider_fit_options,
    slider_ingest_options,
)

HEADER = "record_id\tmat\trole\tstiffness_n_m\tdrive_speed_um_s\tmass_g\tnormal_load_n\twindow_s\n"


def _table(tmp_path: Path, rows: str, header: str = HEADER) -> Path:
    path = tmp_path / "sliders.tsv"
    path.write_text("# a comment\n" + header + rows)
    return path


def test_the_colas_campaign_is_read() -> None:
    table = read_slider_campaign(Path(__file__).parents[1] / "config/colas.tsv")
    assert list(table.index[:3]) == ["k168_v42", "k168_v1100", "k168_v4300"]
    assert (table["role"] == "fit").sum() == 6
    assert set(table.loc[table["role"] == "predict", "stiffness_n_m"]) == {2254}
    assert table["normal_load_n"].iloc[0] == pytest.approx(0.0307 * 9.81)


def test_a_given_normal_load_is_kept(tmp_path: Path) -> None:
    table = read_slider_campaign(_table(tmp_path, "r1\ta.mat\tfit\t168\t42\t30.7\t0.5\t10\n"))
    assert table.loc["r1", "normal_load_n"] == 0.5
    assert slider_ingest_options(table.loc["r1"]) == (
        "--role fit --stiffness 168.0 --drive-speed 42.0 --mass 30.7 --normal-load 0.5 "
        "--window 10.0")


@pytest.mark.parametrize(("rows", "message"), [
    ("r1\ta.mat\ttrain\t168\t42\t30.7\t\t10\n", "line 3.*role"),
    ("r1\ta.mat\tfit\tstiff\t42\t30.7\t\t10\n", "line 3.*stiffness_n_m"),
    ("r1\ta.mat\tfit\t168\t42\t30.7\t\t10\nr1\tb.mat\tfit\t168\t42\t30.7\t\t10\n",
     "'r1' appears twice"),
    ("r1\ta.mat\tpredict\t168\t42\t30.7\t\t10\n", "nothing to fit"),
])
def test_a_faulty_table_is_refused_with_its_line(tmp_path: Path, rows: str, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        read_slider_campaign(_table(tmp_path, rows))


def test_a_missing_table_is_named(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="not found"):
        read_slider_campaign(tmp_path / "none.tsv")


def test_the_fit_options_are_the_settings() -> None:
    assert slider_fit_options({**SLIDER_DEFAULTS, "evolution": "aging", "cutoff": False}) == (
        "--states 1 --members 4 --design 8 --acquisitions 24 --exploration 2.0 --samples 2000 "
        "--seed 0 --evolution aging --no-cutoff")

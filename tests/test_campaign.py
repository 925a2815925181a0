from __future__ import annotations

import pytest

from slipwave.campaign import column_arguments, column_map, read_campaign
from slipwave.errors import ConfigError


def test_read_campaign_fills_optional_columns(write):
    table = read_campaign(write("test_id\tcsv\na\tx.csv\nb\ty.csv\n", "t.tsv"))
    assert list(table.index) == ["a", "b"]
    assert table.loc["b", "frames"] == "" and table.loc["a", "columns"] == ""


def test_duplicate_test_id_names_line(write):
    path = write("test_id\tcsv\na\tx.csv\nb\ty.csv\na\tz.csv\n", "t.tsv")
    with pytest.raises(ConfigError, match=r"t.tsv, line 4: test_id 'a' appears twice"):
        read_campaign(path)


def test_missing_csv_column(write):
    with pytest.raises(ConfigError, match=r"line 1: no 'csv' column"):
        read_campaign(write("test_id\tpath\na\tx.csv\n", "t.tsv"))


def test_missing_table(tmp_path):
    with pytest.raises(ConfigError, match="campaign table not found"):
        read_campaign(tmp_path / "none.tsv")


def test_column_maps():
    config = {"column_maps": {"fr": {"Temps": "time", "Effort x": "T"}}}
    assert column_map(config, "fr") == {"Temps": "time", "Effort x": "T"}
    assert column_map(config, "") == {}
    assert column_arguments(config, "fr") == "--column=Temps=time '--column=Effort x=T'"
    with pytest.raises(ConfigError, match=r"column map 'de' is not in the config's column_maps"):
        column_map(config, "de")

from __future__ import annotations

import pytest

from slipwave.campaign import (
    check_campaign,
    check_config_files,
    column_map,
    column_pairs,
    read_campaign,
    setup_cells,
)
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
    assert column_pairs(config, "fr") == ["Temps=time", "Effort x=T"]
    with pytest.raises(ConfigError, match=r"column map 'de' is not in the config's column_maps"):
        column_map(config, "de")


def test_setup_cells_pass_only_the_filled_configuration_columns():
    row = {"test_id": "a", "height_mm": "40", "poisson_ratio": "", "edge_reference": "flat",
           "frames": "x.mkv"}
    assert setup_cells(row) == ["height_mm=40", "edge_reference=flat"]


def test_check_campaign_names_the_test_with_an_unknown_map(write):
    table = read_campaign(write("test_id\tcsv\tcolumns\na\tx.csv\nb\ty.csv\tde\n", "t.tsv"))
    config = {"detection": {"gross_edge_ratio": 0.9}, "column_maps": {"fr": {"Temps": "time"}}}
    with pytest.raises(ConfigError, match=r"t.tsv, line 3 \(test 'b'\): column map 'de' is not"):
        check_campaign(config, table)


def test_campaign_tables_and_configs(write, tmp_path):
    with pytest.raises(ConfigError, match=r"t\.tsv: no test: the table has a header but no row"):
        read_campaign(write("# a campaign\ntest_id\tcsv\n", "t.tsv"))
    table = read_campaign(write("# comment\n\ntest_id\tcsv\na\tx.csv\n# gone\nb\ty.csv\n",
                                "u.tsv"))
    assert table.attrs["lines"] == {"a": 4, "b": 6}
    config = tmp_path / "mine.yaml"
    config.write_text("column_maps: {}\n")
    with pytest.raises(ConfigError, match=r"mine\.yaml: no 'tests' entry naming the campaign"):
        check_config_files([config], command_line=[config])
    check_config_files([config])  # the workflow's own config only: fine

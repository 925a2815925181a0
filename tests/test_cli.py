from __future__ import annotations

import numpy as np

from slipwave.cli import main
from slipwave.io import read_dataset

from conftest import CANONICAL


def test_ingest_writes_netcdf(write, tmp_path, capsys):
    out = tmp_path / "sub" / "rec.nc"
    assert main(["ingest", str(write(CANONICAL)), "-o", str(out)]) == 0
    assert read_dataset(out)["T"].values.tolist() == [0.5, 1.5, 2.5, 3.5]
    assert "4 samples" in capsys.readouterr().out


def test_ingest_column_options(write, tmp_path):
    path = write("Horloge (ms);Cis (N);Serrage (N)\n0;1;-2\n10;2;-3\n")
    out = tmp_path / "rec.nc"
    code = main(["ingest", str(path), "-o", str(out), "--columns", "Horloge=time",
                 "Cis=T", "Serrage=N"])
    assert code == 0
    np.testing.assert_allclose(read_dataset(out)["time"].values, [0.0, 0.01])


def test_ingest_error_is_one_clean_line(write, tmp_path, capsys):
    out = tmp_path / "rec.nc"
    code = main(["ingest", str(write(CANONICAL.replace("2.5,-81.0", "2.5,abc"))), "-o", str(out)])
    assert code == 1
    err = capsys.readouterr().err
    assert err.startswith("slipwave: error: ") and "line 11, column 'N [N]'" in err
    assert "Traceback" not in err and not out.exists()


def test_ingest_warnings_on_stderr(write, tmp_path, capsys):
    main(["ingest", str(write(CANONICAL + "0.04,1")), "-o", str(tmp_path / "r.nc")])
    assert "truncated last line" in capsys.readouterr().err


def test_report_page(write, tmp_path):
    rec = tmp_path / "rec.nc"
    main(["ingest", str(write(CANONICAL)), "-o", str(rec)])
    page = tmp_path / "page.html"
    assert main(["report", str(rec), "-o", str(page)]) == 0
    html = page.read_text()
    assert "<h1>Test t1</h1>" in html and "data:image/png;base64," in html
    assert "tangential load" in html and "normal_load_n" in html


def test_sawtooth_writes_three_tests(tmp_path):
    assert main(["sawtooth", str(tmp_path), "--seed", "4"]) == 0
    assert sorted(p.name for p in tmp_path.glob("*.csv")) == [
        "saw_hl025.csv", "saw_hl050.csv", "saw_hl075.csv"]


def test_an_unexpected_exception_is_one_line_and_a_log(monkeypatch, tmp_path, capsys):
    def broken(args):
        raise ZeroDivisionError("a bug")

    monkeypatch.setattr("slipwave.cli._summary", broken)
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    import tempfile

    monkeypatch.setattr(tempfile, "tempdir", None)
    (tmp_path / "x.nc").write_text("")
    assert main(["summary", str(tmp_path / "x.nc"), "-o", str(tmp_path / "y.csv")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "internal error (ZeroDivisionError: a bug)" in err
    log = next(tmp_path.glob("slipwave-crash-*.log"))
    assert "Traceback" in log.read_text() and str(log) in err


def test_the_condensations_are_kept_only_where_a_folder_is_named(tmp_path, monkeypatch):
    home = tmp_path / "home"
    home.mkdir()
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.delenv("XDG_CACHE_HOME", raising=False)
    monkeypatch.delenv("SLIPWAVE_CACHE_DIR", raising=False)
    out = tmp_path / "out"
    assert main(["simulate", "--fs", "1", "--elements", "8", "-o", str(out / "s.nc")]) == 0
    assert [path.name for path in out.iterdir()] == ["s.nc"]
    assert list(home.iterdir()) == []  # nothing under ~/.cache
    kept = tmp_path / "kept"
    assert main(["simulate", "--fs", "1", "--elements", "8", "-o", str(out / "s.nc"),
                 "--cache-dir", str(kept)]) == 0
    assert len(list(kept.glob("condensed-*.npz"))) == 1

"""numba's cached kernels are removed when any of the package's sources changes."""

from __future__ import annotations

from pathlib import Path

from slipwave.kernel_sources import DIGEST_FILE, clear_stale_kernels, sources_digest


def _package(folder: Path) -> Path:
    package = folder / "pkg"
    (package / "sub" / "__pycache__").mkdir(parents=True)
    (package / "caller.py").write_text("def caller():\n    return callee()\n")
    (package / "sub" / "callee.py").write_text("def callee():\n    return 1\n")
    return package


def _cache(package: Path) -> list[Path]:
    cached = [package / "sub" / "__pycache__" / name
              for name in ("callee.callee-1.py311.nbi", "callee.callee-1.py311.1.nbc")]
    for path in cached:
        path.write_bytes(b"compiled")
    return cached


def test_an_edited_callee_clears_every_cached_kernel(tmp_path: Path) -> None:
    package = _package(tmp_path)
    cached = _cache(package)
    assert clear_stale_kernels(package)  # no digest yet: built from unknown sources
    assert not any(path.exists() for path in cached)
    assert (package / "__pycache__" / DIGEST_FILE).read_text() == sources_digest(package)
    cached = _cache(package)
    assert not clear_stale_kernels(package)  # the same sources: the caches stay
    assert all(path.exists() for path in cached)
    (package / "sub" / "callee.py").write_text("def callee():\n    return 2\n")
    assert clear_stale_kernels(package)
    assert not any(path.exists() for path in cached)


def test_the_digest_follows_paths_and_contents(tmp_path: Path) -> None:
    package = _package(tmp_path)
    first = sources_digest(package)
    (package / "sub" / "callee.py").rename(package / "sub" / "other.py")
    assert sources_digest(package) != first

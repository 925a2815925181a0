"""numba's disk cache of the package's kernels, kept to the sources they were built from.

numba invalidates a kernel's cache when the kernel's own file changes, not when a
function it calls from another file does, though that function's code is compiled into
it (numba's documentation: "Cache invalidation fails to recognize changes in functions
defined in a different file"). An edited callee would then live on, unseen, in every
caller cached from another module: the quasi-dynamic stretch's loop kept running an
earlier BDF step after ``stiff_steps.py`` had changed. So the package's sources are
hashed when it is imported, and where the digest differs from the one its cached
kernels were built from, those caches are removed and numba builds them afresh.

Only the caches beside the sources (numba's ``__pycache__``, where an editable or
writable install keeps them) are looked after; a read-only install's kernels live in
numba's own cache folder, whose files a new install does not reuse either way.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent
DIGEST_FILE = "numba-sources.sha256"
"""Where the digest of the sources the cached kernels were built from is kept, in the
package's ``__pycache__``."""


def sources_digest(package: Path = PACKAGE) -> str:
    """The SHA-256 of a package's Python sources: their paths and contents, in order.

    Parameters
    ----------
    package
        The package's folder.

    Returns
    -------
    str
        The hexadecimal digest.
    """
    digest = hashlib.sha256()
    for source in sorted(package.rglob("*.py")):
        digest.update(source.relative_to(package).as_posix().encode())
        digest.update(source.read_bytes())
    return digest.hexdigest()


def clear_stale_kernels(package: Path = PACKAGE) -> bool:
    """Remove the package's cached kernels if its sources changed since they were built.

    Parameters
    ----------
    package
        The package's folder.

    Returns
    -------
    bool
        Whether caches were removed (the sources' digest was new).

    Examples
    --------
    >>> clear_stale_kernels()  # the sources as they were at the last import
    False
    """
    digest = sources_digest(package)
    stamp = package / "__pycache__" / DIGEST_FILE
    try:
        if stamp.read_text(encoding="ascii") == digest:
            return False
    except OSError:
        pass
    for cached in [*package.rglob("*.nbi"), *package.rglob("*.nbc")]:
        # gone already (another process's removal), or a read-only install
        with contextlib.suppress(OSError):
            cached.unlink()
    try:
        stamp.parent.mkdir(exist_ok=True)
        partial = stamp.with_name(f"{DIGEST_FILE}.{os.getpid()}")
        partial.write_text(digest, encoding="ascii")
        partial.replace(stamp)  # whole, for the processes starting beside this one
    except OSError:
        pass
    return True

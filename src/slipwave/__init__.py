"""slipwave: friction-bench recordings to answers.

Ingest acquisition-card CSVs (:mod:`slipwave.io`), detect stick, partial-slip and
gross-slip events, simulate the bench with a frictional-contact solver and build
comparison reports, as a library and as a Snakemake workflow.
"""

from importlib.metadata import PackageNotFoundError, version

from slipwave.errors import AcquisitionError, SlipwaveError
from slipwave.kernel_sources import clear_stale_kernels

# numba does not see a change in a kernel's callees from other files: their caches are
# dropped whenever the package's sources differ from those they were built from
clear_stale_kernels()

try:
    __version__ = version("slipwave")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0+unknown"

__all__ = ["AcquisitionError", "SlipwaveError", "__version__"]

"""slipwave: friction-bench recordings to answers.

Ingest acquisition-card CSVs (:mod:`slipwave.io`), detect stick, partial-slip and
gross-slip events, simulate the bench with a frictional-contact solver and build
comparison reports, as a library and as a Snakemake workflow.
"""

from importlib.metadata import PackageNotFoundError, version

from slipwave.errors import AcquisitionError, SlipwaveError

try:
    __version__ = version("slipwave")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0+unknown"

__all__ = ["AcquisitionError", "SlipwaveError", "__version__"]

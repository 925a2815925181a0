"""The recorded channels, their CF attributes, and the reader's own attributes."""

from __future__ import annotations

CHANNELS: tuple[str, ...] = ("T", "N", "DG", "DD", "DT")
"""The recorded channels, in file order; ``time`` is the dimension."""

REQUIRED_CHANNELS: tuple[str, ...] = ("T",)

CHANNEL_ATTRS: dict[str, dict[str, str]] = {
    "time": {"units": "s", "long_name": "time since the start of the acquisition", "axis": "T"},
    "T": {"units": "N", "long_name": "tangential load"},
    "N": {"units": "N", "long_name": "normal load"},
    "DG": {"units": "mm", "long_name": "left-edge lateral displacement of the slab"},
    "DD": {"units": "mm", "long_name": "right-edge lateral displacement of the slab"},
    "DT": {"units": "mm", "long_name": "flat displacement (imposed travel)"},
}


# Reader-made global attributes: a metadata key with one of these names is kept
# under ``meta_<key>`` so that the file cannot overwrite provenance.
RESERVED_ATTRS = frozenset(
    {"Conventions", "source", "source_sha256", "warnings", "missing_channels",
     "source_format", "history"}
)

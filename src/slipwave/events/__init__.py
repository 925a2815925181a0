"""Events of a friction test: load drops, edge jumps, slips, phases, friction ratios.

Detection is composable, in the manner of a seismic trigger: a characteristic
signal and its noise (:func:`noise_level`, :func:`despike`, :func:`without_spikes`),
thresholds and
events (:func:`load_drops`, :func:`edge_jumps`), then slips (:func:`classify_events`,
all of it on a recording: :func:`detect_events`). :func:`events_dataset` and
:func:`events_table` are the one conversion between the events table and
``events.nc``; :mod:`slipwave.events.summary` says what the events mean for a test.
"""

from slipwave.events.detect import (
    EVENT_COLUMNS,
    EVENT_DESCRIPTIONS,
    EVENT_UNITS,
    DetectionSettings,
    classify_events,
    detect_events,
    events_dataset,
    events_table,
)
from slipwave.events.steps import (
    STEP_COLUMNS,
    despike,
    edge_jumps,
    load_drops,
    noise_level,
    without_spikes,
)
from slipwave.events.summary import (
    PHASES,
    friction_ratio,
    load_ratio,
    normal_loading_end,
    phase_durations,
    phase_labels,
    segment_phases,
    summary_row,
    wave_counts,
)

__all__ = [
    "EVENT_COLUMNS",
    "EVENT_DESCRIPTIONS",
    "EVENT_UNITS",
    "PHASES",
    "STEP_COLUMNS",
    "DetectionSettings",
    "classify_events",
    "despike",
    "detect_events",
    "edge_jumps",
    "events_dataset",
    "events_table",
    "friction_ratio",
    "load_drops",
    "load_ratio",
    "noise_level",
    "normal_loading_end",
    "phase_durations",
    "phase_labels",
    "segment_phases",
    "summary_row",
    "wave_counts",
    "without_spikes",
]

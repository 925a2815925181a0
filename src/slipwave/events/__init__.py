"""Events of a friction test: load drops, edge jumps, slips, phases, friction ratios."""

from slipwave.events.slips import (
    EVENT_COLUMNS,
    EVENT_DESCRIPTIONS,
    EVENT_UNITS,
    classify_events,
    detect_events,
)
from slipwave.events.steps import (
    STEP_COLUMNS,
    despike,
    edge_jumps,
    fall_candidates,
    load_drops,
    noise_level,
    refine_step,
)
from slipwave.events.summary import (
    PHASES,
    events_dataset,
    friction_ratio,
    normal_loading_end,
    phase_durations,
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
    "classify_events",
    "despike",
    "detect_events",
    "edge_jumps",
    "events_dataset",
    "fall_candidates",
    "friction_ratio",
    "load_drops",
    "noise_level",
    "normal_loading_end",
    "phase_durations",
    "refine_step",
    "segment_phases",
    "summary_row",
    "wave_counts",
]

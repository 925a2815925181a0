"""Compiled steps over a stretch of unchanged contact, and what each step records.

The driver (:mod:`slipwave.solver.quasi_dynamic`) hands a stretch to :func:`advance`,
which takes BDF steps (:mod:`slipwave.solver.stiff_steps`) and records after each the
loads and sensors at the sample times it passed, the state at the field times it passed
and the nodes whose slip rate crossed the front speed, until the contact must change, a
buffer is full or the run ends; the driver then does what needs the whole body (the
fields of the states held, the contact's change) and hands the stretch back. A step's
Python dispatch (the stepper's, the reduction's and the law's arrays unboxed at every
call) cost as much as a third of the step, and a return to Python at each field time
half of a coarse mesh's run.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from slipwave.solver.quasi_dynamic_steps import Law, Reduction, readouts, step_end
from slipwave.solver.stiff_steps import BOUND, OK, T_OLD, Stepper, T, interpolate, step

PASSED, CHANGES, FULL, TOO_SMALL = range(4)
"""What :func:`advance` returns: the time it was to pass is passed (or the end); the
contact changes within the last step (not recorded); the crossings' or the field states'
buffer is full; a step fell below the smallest."""

# the places in Record.cursor
NEXT_SAMPLE, CROSSINGS, NEXT_FIELD, FIELDS_HELD = range(4)


class Record(NamedTuple):
    """What steps record, filled in place.

    Attributes
    ----------
    sample_times
        The times of the samples.
    samples
        (readouts + 2, sample_times): the readouts, dx and dy at each (NaN until taken).
    crossing_node, crossing_time, crossing_rising
        The buffer of crossings: the node, the time, 1 where the slip rate rises.
    field_times
        The times of the fields.
    field_states
        (rows, state size): the buffer of states at the field times, the first held at
        ``field_times[cursor[NEXT_FIELD] - cursor[FIELDS_HELD]]``.
    cursor
        The next sample to take, the crossings held in the buffer, the next field time
        to take, the field states held in the buffer.
    speeds
        The closed nodes' slip rates at the last recorded step's end.
    """

    sample_times: np.ndarray
    samples: np.ndarray
    crossing_node: np.ndarray
    crossing_time: np.ndarray
    crossing_rising: np.ndarray
    field_times: np.ndarray
    field_states: np.ndarray
    cursor: np.ndarray
    speeds: np.ndarray


@njit(cache=True)
def record_step(stepper: Stepper, reduction: Reduction, law: Law, begin: float, end: float,
                after: np.ndarray, front_speed: float, record: Record) -> None:
    """Record a step from ``begin`` to ``end`` from its interpolant.

    The samples that fall in it; the states at the field times that do, as many as the
    buffer has room for; the closed nodes whose slip rate crossed ``front_speed``, each
    at the time interpolated in the logarithm of the rate.

    Parameters
    ----------
    stepper
        The stepper after the step (its interpolant).
    reduction, law
        The contact.
    begin, end
        The part of the step to record.
    after
        The closed nodes' slip rates at ``end``.
    front_speed
        The slip rate whose crossing is a front's passage.
    record
        The record, updated; its ``speeds`` become ``after``.
    """
    times, cursor = record.sample_times, record.cursor
    first = cursor[NEXT_SAMPLE]
    stop = np.searchsorted(times, end, side="right")
    if stop > first:
        chosen = times[first:stop]
        record.samples[:, first:stop] = readouts(chosen, interpolate(stepper, chosen),
                                                 reduction, law)
        cursor[NEXT_SAMPLE] = stop
    fields, held = cursor[NEXT_FIELD], cursor[FIELDS_HELD]
    stop = min(np.searchsorted(record.field_times, end, side="right"),
               fields + record.field_states.shape[0] - held)
    if stop > fields:
        record.field_states[held:held + stop - fields] = interpolate(
            stepper, record.field_times[fields:stop]).T
        cursor[NEXT_FIELD], cursor[FIELDS_HELD] = stop, held + stop - fields
    before = record.speeds
    for k in range(after.size):
        was, now = abs(before[k]), abs(after[k])
        if (was < front_speed) == (now < front_speed):
            continue
        if was > 0.0 and now > 0.0:
            share = np.log(front_speed / was) / np.log(now / was)
        else:
            share = (front_speed - was) / (now - was)
        held = cursor[CROSSINGS]
        record.crossing_node[held] = reduction.closed[k]
        record.crossing_time[held] = begin + share * (end - begin)
        record.crossing_rising[held] = now >= front_speed
        cursor[CROSSINGS] = held + 1
    record.speeds[:] = after


@njit(cache=True)
def advance(stepper: Stepper, reduction: Reduction, law: Law, band: int, force_scale: float,
            gap_scale: float, until: float, front_speed: float, record: Record) -> int:
    """Step and record until ``until`` or the end is reached, or the contact changes.

    Parameters
    ----------
    stepper
        The stepper, updated in place.
    reduction, law
        The contact.
    band
        The Jacobian's half-width.
    force_scale, gap_scale
        The margin's units (:func:`~slipwave.solver.quasi_dynamic_steps.step_end`).
    until
        The time after which to return.
    front_speed
        The slip rate whose crossing is a front's passage.
    record
        The record, updated.

    Returns
    -------
    int
        :data:`PASSED`, :data:`CHANGES` (the last step is taken but not recorded: the
        contact's margin fell below -1 within it), :data:`FULL` or :data:`TOO_SMALL`.
    """
    sc = stepper.scalars
    room = record.crossing_node.size - reduction.closed.size  # a step's crossings fit
    while True:
        if (record.cursor[CROSSINGS] > room
                or record.cursor[FIELDS_HELD] == record.field_states.shape[0]):
            return FULL
        if step(stepper, reduction, law, band) != OK:
            return TOO_SMALL
        end = sc[T]
        margin, after = step_end(end, stepper.D[0], reduction, law, force_scale, gap_scale)
        if margin < -1.0:
            return CHANGES
        record_step(stepper, reduction, law, sc[T_OLD], end, after, front_speed, record)
        if end >= until or end >= sc[BOUND]:
            return PASSED

"""The fit stage: a test's friction law, inferred from its slips through the solver.

A package split by job:

- :mod:`~slipwave.fit.features`: the slips a fit compares, detected alike in the
  recording and in each simulation, summed up as one feature vector;
- :mod:`~slipwave.fit.laws`: the laws, their parameters and priors;
- :mod:`~slipwave.fit.ensemble`: K simulations per guess over what the recording does
  not fix (calibration, normal load, stiffness, speed, noise, the cycle's start);
- :mod:`~slipwave.fit.likelihood`: the Gaussian synthetic likelihood (Wood 2010);
- :mod:`~slipwave.fit.law_search`: each law's posterior, from Gaussian-process
  emulators of its ensemble's features (:mod:`~slipwave.fit.emulator`) sampled by
  emcee, and its evidence (:mod:`~slipwave.fit.search`);
- :mod:`~slipwave.fit.procedure`: a test's laws fitted, the law of highest evidence
  chosen, its posterior predictive checked feature by feature, its mesh checked;
- :mod:`~slipwave.fit.output`: ``fit.json`` read back.
"""

from slipwave.fit.features import (
    FEATURES,
    SlipFeatures,
    detected_edge_threshold,
    edge_threshold,
    measured_events,
    simulated_events,
    simulated_recording,
    slip_features,
)
from slipwave.fit.laws import LAWS, PRIORS, law_of
from slipwave.fit.output import chosen_law, read_fit
from slipwave.fit.procedure import FitSettings, fit_test

__all__ = ["FEATURES", "LAWS", "PRIORS", "FitSettings", "SlipFeatures", "chosen_law",
           "detected_edge_threshold", "edge_threshold", "fit_test", "law_of",
           "measured_events", "read_fit", "simulated_events", "simulated_recording",
           "slip_features"]

"""Default values of slipwave's parameters: the one place the library and the CLI take them from.

The workflow's settings and their defaults are written once, in the configuration's
schema (``slipwave/schemas/config.schema.json``, each with its meaning and unit):
Snakemake's ``validate`` fills them into a campaign's config, and this module reads
them from there, so a parameter can be followed from ``config/config.yaml`` through
the rule's ``params:`` and the CLI option to the function argument that uses it.
The bench's constants, which no campaign sets, are written here.

Units are the project's: mm, N, MPa, s.
"""

from __future__ import annotations

from typing import Any, Final

from slipwave.validation import load_schema

_SETTINGS = load_schema("config")["properties"]


def setting_schema(section: str, key: str) -> dict[str, Any]:
    """The schema of the setting ``section.key`` (its type, bounds and default).

    Parameters
    ----------
    section, key
        The setting, e.g. ``"fit"``, ``"load_calibration"``.

    Returns
    -------
    dict
        Its JSON schema; the command line checks its options against it.

    Examples
    --------
    >>> setting_schema("fit", "members")["minimum"]
    2
    """
    return dict(_SETTINGS[section]["properties"][key])


def _setting(section: str, key: str) -> Any:
    """The schema's default of ``section.key``."""
    return setting_schema(section, key)["default"]


CONVENTIONS = "CF-1.12"
"""CF conventions the netCDF outputs follow."""

# The bench: slab, material and loading of the paper's test.
CONTACT_LENGTH_MM: float = _setting("video", "length_mm")
"""Length L of the slab along the contact, mm (also the image scale of the video)."""
SLAB_HEIGHT_MM = 40.0
"""Height H of the slab, mm (H/L = 0.5, the paper's figure 5)."""
SLAB_WIDTH_MM = 10.0
"""Out-of-plane width w of the slab, mm."""
YOUNGS_MODULUS_MPA = 7.0
"""Young's modulus of the polyurethane, MPa."""
POISSON_RATIO = 0.48
"""Poisson's ratio of the polyurethane."""
NORMAL_LOAD_N = 76.0
"""Normal load imposed before the tangential loading in the paper's numerical study, N."""
TANGENTIAL_STEP_N = 2.0
"""Tangential load increment of the paper's numerical study, N."""
NORMAL_CONTROL: Final = "displacement"
"""What a load path holds after the normal loading by default: the flat's normal
position (the bench's step 2); ``force`` holds N."""
NORMAL_FRICTION = True
"""Whether friction acts during a load path's normal loading by default (the flat is
pressed with friction, as on the bench)."""
TRAVEL_STEP_MM = 0.03
"""The actuator's travel per load step when a test is driven through its machine, mm."""
SLAB_ELEMENTS = 160
"""Elements along the contact of a slab simulated alone (``Slab``, ``slipwave simulate``
without a fit)."""
BENCH_ELEMENTS = 160
"""Elements along the contact of the virtual bench's tests: twice the fit's, the mesh
the fit carries its features to (``slipwave.fit.ensemble.mesh_error``'s shift), so a fit
of a test made here is in part a fit with the model that made it; the calibration
benchmark makes its tests at four times the fit's."""

# The behaviour map (slipwave.map; config section ``map``).
MAP_ELEMENTS: int = _setting("map", "elements")
"""Elements along the contact of the map's cases."""
MAP_BAND_STEPS: int = _setting("map", "band_steps")
"""f steps by which the map's band (where it still moves with the mesh) is widened."""
MIN_ZONE_MM: float = _setting("map", "min_zone_mm")
"""Shortest zone (mm) that decides a behaviour."""
MAP_NORMAL_CONTROL: str = _setting("map", "normal_control")
"""What the map holds after the normal loading: ``force`` (N, the paper's setting) or
``displacement`` (the flat's normal position)."""
MAP_NORMAL_FRICTION: bool = _setting("map", "normal_friction")
"""Whether friction acts during the map's normal loading."""
MAP_FRICTIONS: tuple[float, float, float] = tuple(_setting("map", "frictions"))
"""The map's friction coefficients: start, stop (included), step."""
MAP_HEIGHT_RATIOS: tuple[float, ...] = tuple(_setting("map", "height_ratios"))
"""The map's slab slendernesses H/L (the paper's)."""

# Event detection (slipwave.events; config section ``detection``).
THRESHOLD: float = _setting("detection", "threshold")
"""Default drop and jump thresholds, in noise standard deviations."""
MAX_SPIKE: int = _setting("detection", "max_spike")
"""Longest spike (samples) that detection ignores."""
MAX_DURATION_S: float | None = _setting("detection", "max_duration")
"""Longest drop looked for, s; ``None``: a tenth of the recording."""
MIN_ASYMMETRY = 3.0
"""How many times faster than the rise before it an edge step must be (edge_jumps)."""
MIN_FALL_RATE: float = _setting("detection", "min_fall_rate")
"""How many times faster than the drive's loading rate a load must fall to be a slip."""
GROSS_EDGE_RATIO: float = _setting("detection", "gross_edge_ratio")
"""DG jump / DD jump from which a T drop is a gross slip."""
EDGE_CONVENTION: str = _setting("detection", "edge_convention")
"""How the edge sensors read: ``x_axis`` (both along +x), ``outward`` (each its own edge's
outward displacement, the paper's bench), or ``auto`` (found from the stick ramps)."""

# Video analysis (slipwave.video; config section ``video``).
BAND_MM: tuple[float, float] = tuple(_setting("video", "band_mm"))
"""Band of the kymograph, mm above the interface (low, high)."""
PAIRING_TOLERANCE_S = 0.3
"""Largest gap between a wave's start and a load event's onset that pairs them, s."""

# The fit of friction laws (slipwave.fit; config section ``fit``).
FIT_LAWS: tuple[str, ...] = tuple(_setting("fit", "laws"))
"""The laws each test is fitted with."""
FIT_ELEMENTS: int = _setting("fit", "elements")
"""Elements along the contact in the fit's simulations (and the test's simulation)."""
FIT_TUNABLES: tuple[str, ...] = ("members", "stiffness_error", "speed_error", "step_jitter",
                                  "ratio_error", "time_error_s", "design", "refinements",
                                  "draw_temperature", "samples", "predictive_members", "seed")
"""The fit's numeric settings besides the mesh and the calibration (the ensemble, the
measurement's errors, the search), each an option of ``slipwave fit`` of its name."""
FIT_DEFAULTS: dict[str, Any] = {key: _setting("fit", key) for key in FIT_TUNABLES}
"""Their defaults."""
FIT_MESH_CHECK: bool = _setting("fit", "mesh_check")
"""Whether the chosen law is refitted at twice the fit's mesh (its parameters' change)."""
LOAD_CALIBRATION: float = _setting("fit", "load_calibration")
"""Relative calibration uncertainty of each load cell (T and N), one standard deviation."""
SAMPLE_RATE_HZ = 100.0
"""Sampling rate of a simulated test's recording, Hz (the virtual bench's card)."""

# The quasi-dynamic simulation of filmed tests (slipwave.simulate_waves; ``simulate_waves``).
WAVES_LAW: dict[str, float] = {key: _setting("simulate_waves", key)
                               for key in ("a", "b", "dc_um", "mu0", "v0_um_s")}
"""The rate-and-state law the filmed tests' waves are simulated with."""
WAVES_ELEMENTS: int = _setting("simulate_waves", "elements")
"""Elements along the contact of those simulations."""
WAVES_FIELD_RATE_HZ: float = _setting("simulate_waves", "field_rate_hz")
"""Records per second of their nodes' fields."""

# The fit of filmed tests' rate-and-state laws (slipwave.fit_waves; ``fit_waves``).
FIT_WAVES_TUNABLES: tuple[str, ...] = ("elements", "members", "design", "refinements",
                                       "samples", "mesh_checks", "seed")
"""The settings of that fit, each an option of ``slipwave fit-waves`` of its name."""
FIT_WAVES_DEFAULTS: dict[str, int] = {key: _setting("fit_waves", key)
                                      for key in FIT_WAVES_TUNABLES}
"""Their defaults."""

# Spring-slider campaigns (slipwave.fit.slider; config section ``sliders``).
SLIDER_TUNABLES: tuple[str, ...] = ("states", "members", "design", "acquisitions",
                                    "exploration", "samples", "draws", "seed")
"""The spring-slider fit's settings, each an option of ``slipwave slider-fit`` (``draws``:
of ``slipwave slider-predict``) of its name."""
SLIDER_DEFAULTS: dict[str, Any] = {key: _setting("sliders", key) for key in SLIDER_TUNABLES}
"""Their defaults."""
SLIDER_EVOLUTION: str = _setting("sliders", "evolution")
"""The state's evolution law the spring-slider fit uses by default."""
SLIDER_CUTOFF: bool = _setting("sliders", "cutoff")
"""Whether the spring-slider fit's law has a cut-off speed by default."""

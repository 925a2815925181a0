"""Default values of slipwave's parameters: the one place the library and the CLI take them from.

The workflow's defaults are in ``workflow/schemas/config.schema.json`` (Snakemake's
``validate`` fills them into the config); ``tests/test_defaults.py`` checks that the
two agree, so a parameter can be followed from ``config/config.yaml`` through the
rule's ``params:`` and the CLI option to the function argument that uses it.

Units are the project's: mm, N, MPa, s.
"""

from __future__ import annotations

CONVENTIONS = "CF-1.12"
"""CF conventions the netCDF outputs follow."""

# The bench (see DOMAIN.md): slab, material and loading of the paper's test.
CONTACT_LENGTH_MM = 80.0
"""Length L of the slab along the contact, mm (also the image scale of the video)."""
SLAB_HEIGHT_MM = 40.0
"""Height H of the slab, mm (H/L = 0.5, the paper's figure 5)."""
SLAB_WIDTH_MM = 10.0
"""Out-of-plane width w of the slab, mm."""
YOUNGS_MODULUS_MPA = 7.0
"""Young's modulus of the polyurethane, MPa."""
POISSON_RATIO = 0.48
"""Poisson's ratio of the polyurethane."""
CONTACT_ELEMENTS = 160
"""Finite elements along the contact in simulations."""
NORMAL_LOAD_N = 76.0
"""Normal load imposed before the tangential loading in the paper's numerical study, N."""
TANGENTIAL_STEP_N = 2.0
"""Tangential load increment of the paper's numerical study, N."""

# The behaviour map (slipwave.map; config section ``map``).
MIN_ZONE_MM = 1.0
"""Shortest zone (mm) that decides a behaviour: two elements of the 160-element mesh."""
MAP_NORMAL_CONTROL = "force"
"""What the map holds after the normal loading: ``force`` (N, the paper's setting) or
``displacement`` (the flat's normal position)."""
MAP_NORMAL_FRICTION = False
"""Whether friction acts during the map's normal loading (see README, "behaviour map")."""

# Event detection (slipwave.events; config section ``detection``).
THRESHOLD = 8.0
"""Default drop and jump thresholds, in noise standard deviations."""
MAX_SPIKE = 2
"""Longest spike (samples) that detection ignores."""
MAX_DURATION_S: float | None = None
"""Longest drop looked for, s; ``None``: a tenth of the recording."""
MIN_ASYMMETRY = 3.0
"""How many times faster than the rise before it an edge step must be (edge_jumps)."""
MIN_FALL_RATE = 1.2
"""How many times faster than the drive's loading rate a load must fall to be a slip
(the slider then moves at 2.2 times the drive's speed or more)."""
GROSS_EDGE_RATIO = 0.9
"""DG jump / DD jump from which a T drop is a gross slip."""
EDGE_CONVENTION = "auto"
"""How the edge sensors read: ``x_axis`` (both along +x), ``outward`` (each its own edge's
outward displacement, the paper's bench), or ``auto`` (found from the stick ramps)."""

# Video analysis (slipwave.video; config section ``video``).
BAND_MM = (0.5, 2.0)
"""Band of the kymograph, mm above the interface (low, high)."""
PAIRING_TOLERANCE_S = 0.3
"""Largest gap between a wave's start and a load event's onset that pairs them, s."""

# The fit of friction laws (slipwave.fit; config section ``fit``).
FIT_LAWS = ("coulomb", "run-in", "slip-weakening")
"""The laws each test is fitted with."""
FIT_ELEMENTS = 80
"""Elements along the contact in the fit's simulations (and the test's simulation)."""
FIT_MAX_EVALUATIONS = 20
"""Simulations of each law's local search, after its starting scan."""
LOAD_CALIBRATION = 0.005
"""Relative calibration uncertainty of each load cell (T and N), one standard deviation."""

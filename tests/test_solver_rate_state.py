"""Rate-and-state friction and the spring-slider: rsfmodel's cases, the stability boundary."""

from __future__ import annotations

import numpy as np
import pytest

from slipwave.errors import SlipwaveError
from slipwave.solver.rate_state import (
    RateState,
    critical_stiffness,
    friction,
    slip_rate,
    state_rate,
    steady_friction,
)
from slipwave.solver.spring_slider import SpringSlider, _inertial, simulate_spring_slider

# rsfmodel's velocity steps (jrleeman/rsfmodel, tests/rsf_tests.py, MIT licence, (c) 2015
# John Leeman): mu0 0.6, v0 1, k 1e-3 per unit length, Dc 10, the load point stepped
# from 1 to 10 at t = 10, sampled each unit of time from 0 to 40. rsfmodel integrates the
# unregularised law with odeint at rtol 1e-12; the regularisation differs by exp(-240).
DIETERICH = {  # aging law, a 0.005, b 0.01
    "friction": [
        0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.60720485,
        0.60186637, 0.5840091, 0.58563096, 0.58899543, 0.58998186, 0.58879751, 0.58803412,
        0.58825653, 0.58858313, 0.58860319, 0.58848625, 0.58844431, 0.58847472, 0.58849913,
        0.58849522, 0.58848506, 0.58848348, 0.58848674, 0.5884883, 0.58848756, 0.58848677,
        0.5884868, 0.58848711, 0.58848718, 0.5884871, 0.58848704, 0.58848706, 0.58848708,
        0.58848708],
    "state": [
        10., 10., 10., 10., 10., 10., 10., 10., 10., 10., 10., 8.39993716, 2.2355129,
        0.54248237, 0.94936884, 1.21163659, 1.13491241, 0.96889358, 0.94896281, 0.99777122,
        1.01876822, 1.00674821, 0.99515136, 0.9961297, 1.00063816, 1.00161995, 1.00024914,
        0.9994787, 0.99975352, 1.00011844, 1.00012598, 0.99999394, 0.99995185, 0.9999879,
        1.00001411, 1.00000865, 0.99999738, 0.99999604, 0.99999978, 1.00000139, 1.00000049],
    "slider_speed": [
        1., 1., 1., 1., 1., 1., 1., 1., 1., 1., 1., 5.98760938, 29.06408439, 13.87639287,
        6.26688086, 7.54067754, 10.46913416, 11.33475717, 10.14281987, 9.59208664,
        9.82182937, 10.0981912, 10.09601357, 9.99203098, 9.9626088, 9.99173502, 10.01132361,
        10.00641151, 9.99774235, 9.99697087, 9.99992839, 10.00109331, 10.00035175,
        9.99970252, 9.99978205, 10.00004456, 10.00009344, 10.00001142, 9.99996902,
        9.99998658, 10.0000074],
}
RUINA = {  # slip law, a 0.01, b 0.005
    "friction": [
        0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.60839299, 0.6146288,
        0.61663335, 0.61451424, 0.61239234, 0.61152559, 0.61133979, 0.61138186, 0.61145348,
        0.61149781, 0.61151494, 0.61151781, 0.61151612, 0.61151421, 0.61151317, 0.61151282,
        0.61151279, 0.61151285, 0.6115129, 0.61151292, 0.61151293, 0.61151293, 0.61151293,
        0.61151293, 0.61151293, 0.61151293, 0.61151293, 0.61151293, 0.61151293, 0.61151293],
    "slider_speed": [
        1., 1., 1., 1., 1., 1., 1., 1., 1., 1., 1., 2.40532918, 5.50394141, 10.60027612,
        12.69404325, 11.42856179, 10.42488359, 10.02133885, 9.92544961, 9.93937282,
        9.97125078, 9.99210081, 10.00053876, 10.00216595, 10.00149419, 10.00063054,
        10.00013668, 9.99996121, 9.99994058, 9.99996436, 9.99998669, 9.99999803, 10.0000015,
        10.00000156, 10.00000083, 10.00000027, 10.00000002, 9.99999995, 9.99999996,
        9.99999998, 9.99999999],
}
DIETERICH_TWO = {  # aging law, a 0.012, b 0.0185 (Dc 5), b2 0.0088 (Dc2 50), k 3e-3
    "friction": [
        0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.61777816, 0.56719338,
        0.57926411, 0.58134415, 0.5741353, 0.57495495, 0.57393578, 0.57211002, 0.5714098,
        0.57046462, 0.56953958, 0.56884951, 0.56819716, 0.56762505, 0.56715188, 0.56674236,
        0.5663961, 0.56610841, 0.56586767, 0.565668, 0.56550353, 0.56536809, 0.56525698,
        0.56516614, 0.56509194, 0.56503146, 0.56498223, 0.5649422, 0.56490967, 0.56488327
    ],
    "state": [
        5.0, 5.0, 5.0, 5.0, 5.0, 5.0, 5.0, 5.0, 5.0, 5.0, 5.0, 2.80081321, 0.26257732,
        0.67749062, 0.5128508, 0.43041648, 0.506089, 0.47944593, 0.47554365, 0.48734539,
        0.4843392, 0.48564166, 0.48855901, 0.48933082, 0.49072826, 0.4922033, 0.49326055,
        0.49430172, 0.4952396, 0.49601255, 0.49668913, 0.4972666, 0.49774673, 0.49815004,
        0.49848567, 0.49876233, 0.4989905, 0.4991779, 0.4993312, 0.49945649, 0.49955867
    ],
    "state_2": [
        50.0, 50.0, 50.0, 50.0, 50.0, 50.0, 50.0, 50.0, 50.0, 50.0, 50.0, 47.03349418,
        28.26143675, 26.02288006, 22.50536043, 18.45103796, 16.09903009, 13.99322929,
        12.21984746, 10.8626045, 9.74109978, 8.83011044, 8.10068484, 7.50795792, 7.02833114,
        6.64119123, 6.32770427, 6.07410906, 5.86906354, 5.70314217, 5.56890919, 5.46032285,
        5.37246346, 5.30137737, 5.243863, 5.1973259, 5.1596709, 5.12920263, 5.1045488,
        5.08459968, 5.06845739
    ],
    "slider_speed": [
        1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 11.24366669, 9.27431239,
        6.24880306, 12.6979352, 10.55410214, 9.72918973, 10.76583201, 10.34192569, 10.2410124,
        10.3510415, 10.25600829, 10.22005129, 10.20908552, 10.17177535, 10.1462882, 10.126265,
        10.10491673, 10.08761385, 10.07313912, 10.0603132, 10.04968798, 10.04085724,
        10.03343832, 10.02732652, 10.02229955, 10.01816004, 10.01477376, 10.01200822,
        10.00975089, 10.00791305
    ],
}
RUINA_TWO = {  # slip law, the same law, k 8e-3
    "friction": [
        0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.57317487, 0.57620828,
        0.57423257, 0.57241419, 0.57098114, 0.56981792, 0.56887496, 0.56810967, 0.56748807,
        0.56698283, 0.56657196, 0.56623767, 0.56596561, 0.56574412, 0.56556376, 0.56541686,
        0.5652972, 0.56519972, 0.56512029, 0.56505557, 0.56500283, 0.56495985, 0.56492482,
        0.56489628, 0.56487301, 0.56485404, 0.56483859, 0.56482599, 0.56481572, 0.56480735
    ],
    "state": [
        5.0, 5.0, 5.0, 5.0, 5.0, 5.0, 5.0, 5.0, 5.0, 5.0, 5.0, 0.34503501, 0.48718318,
        0.48688665, 0.48906973, 0.49116621, 0.49281743, 0.49415943, 0.49524843, 0.49613296,
        0.4968519, 0.49743656, 0.49791223, 0.49829936, 0.49861453, 0.49887118, 0.4990802,
        0.49925047, 0.49938918, 0.4995022, 0.49959429, 0.49966934, 0.49973049, 0.49978034,
        0.49982096, 0.49985406, 0.49988105, 0.49990304, 0.49992097, 0.49993558, 0.49994749
    ],
    "state_2": [
        50.0, 50.0, 50.0, 50.0, 50.0, 50.0, 50.0, 50.0, 50.0, 50.0, 50.0, 25.46871646,
        19.28091149, 14.94589606, 12.15504322, 10.28679987, 8.98658279, 8.05413768,
        7.36902545, 6.85569405, 6.46493829, 6.16365308, 5.92892636, 5.74450566, 5.59861356,
        5.48255637, 5.38981385, 5.31542877, 5.2555883, 5.20733084, 5.1683369, 5.13677719,
        5.11120066, 5.09045071, 5.07360177, 5.05991069, 5.04877914, 5.03972433, 5.03235598,
        5.0263581, 5.02147453
    ],
    "slider_speed": [
        1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 10.81546891, 10.03428877,
        10.2683735, 10.19823177, 10.16123603, 10.13064517, 10.10597718, 10.08604871,
        10.06991893, 10.05684658, 10.04624063, 10.03762818, 10.03062956, 10.02493909,
        10.02031007, 10.01654309, 10.01347665, 10.01097985, 10.00894645, 10.00729017,
        10.00594089, 10.00484157, 10.00394584, 10.00321593, 10.00262111, 10.00213635,
        10.00174128, 10.00141929, 10.00115686, 10.00094295
    ],
}
NORMAL_LOAD, MASS = 0.301, 0.0307  # N, kg: the Colas slider


def _velocity_step(law: RateState, stiffness: float = 1e-3):  # type: ignore[no-untyped-def]
    bench = SpringSlider(mass=0.0, stiffness=stiffness, drive_speed=1.0, normal_load=1.0)
    return simulate_spring_slider(bench, law, duration=40.0, sample_rate=1.0,
                                  speed_steps=[(10.0, 10.0)])


@pytest.mark.parametrize(("evolution", "a", "b", "truth"),
                         [("aging", 0.005, 0.01, DIETERICH), ("slip", 0.01, 0.005, RUINA)])
def test_velocity_steps_match_rsfmodel(evolution: str, a: float, b: float,
                                       truth: dict[str, list[float]]) -> None:
    law = RateState(a=a, b=b, dc=10.0, mu0=0.6, v0=1.0, evolution=evolution)  # type: ignore[arg-type]
    ds = _velocity_step(law)
    np.testing.assert_allclose(ds.friction_ratio, truth["friction"], rtol=0, atol=2e-8)
    np.testing.assert_allclose(ds.slider_speed, truth["slider_speed"], rtol=1e-6)
    if "state" in truth:
        np.testing.assert_allclose(np.exp(ds.log_state), truth["state"], rtol=1e-6)
    np.testing.assert_allclose(ds.drive_displacement[[10, 11, 40]], [10.0, 20.0, 310.0])


@pytest.mark.parametrize(("evolution", "stiffness", "truth"),
                         [("aging", 3e-3, DIETERICH_TWO), ("slip", 8e-3, RUINA_TWO)])
def test_two_state_velocity_steps_match_rsfmodel(evolution: str, stiffness: float,
                                                 truth: dict[str, list[float]]) -> None:
    law = RateState(a=0.012, b=0.0185, dc=5.0, b2=0.0088, dc2=50.0, mu0=0.6, v0=1.0,
                    evolution=evolution)  # type: ignore[arg-type]
    ds = _velocity_step(law, stiffness)
    np.testing.assert_allclose(ds.friction_ratio, truth["friction"], rtol=0, atol=2e-8)
    np.testing.assert_allclose(ds.slider_speed, truth["slider_speed"], rtol=1e-6)
    np.testing.assert_allclose(np.exp(ds.log_state), truth["state"], rtol=1e-6)
    np.testing.assert_allclose(np.exp(ds.log_state_2), truth["state_2"], rtol=1e-6)


def test_a_second_state_needs_its_length_and_has_no_one_state_bound() -> None:
    with pytest.raises(SlipwaveError, match="second state"):
        RateState(a=0.01, b=0.015, dc=1e-6, mu0=0.4, b2=0.003)
    with pytest.raises(SlipwaveError, match="second state"):
        critical_stiffness(RateState(a=0.01, b=0.015, dc=1e-6, mu0=0.4, b2=0.003, dc2=1e-5),
                           NORMAL_LOAD)


def test_regularised_law_is_the_logarithmic_one_away_from_rest() -> None:
    law = RateState(a=0.01, b=0.015, dc=2e-6, mu0=0.4)
    speed, log_state = np.geomspace(1e-9, 1.0, 7), np.linspace(-8.0, 6.0, 7)
    logarithmic = (law.mu0 + law.a * np.log(speed / law.v0)
                   + law.b * np.log(law.v0 * np.exp(log_state) / law.dc))
    np.testing.assert_allclose(friction(law, speed, log_state), logarithmic, rtol=1e-12)
    np.testing.assert_allclose(slip_rate(law, logarithmic, log_state), speed, rtol=1e-10)
    # odd in the speed; nothing at rest
    np.testing.assert_allclose(friction(law, -speed, log_state), -logarithmic, rtol=1e-12)
    assert friction(law, 0.0, 3.0) == 0.0
    # steady state: mu0 + (a - b) ln(v / v0); the aging state grows 1/theta at rest
    np.testing.assert_allclose(steady_friction(law, [1e-6, 1e-4]),
                               [0.4, 0.4 - 0.005 * np.log(100.0)], rtol=1e-12)
    assert state_rate(law, 0.0, np.log(5.0)) == pytest.approx(0.2)
    slip = RateState(a=0.01, b=0.015, dc=2e-6, mu0=0.4, evolution="slip")
    assert state_rate(slip, 0.0, 3.0) == 0.0
    assert state_rate(slip, 1e-6, np.log(2.0)) == pytest.approx(0.0, abs=1e-12)


def _linear_modes(stiffness: float, law: RateState, mass: float, speed: float) -> np.ndarray:
    """Roots of the law linearised about steady sliding (either evolution law).

    (M/N) Dc s^3 + (M V / N + a Dc / V) s^2 + (a - b + K Dc / N) s + K V / N = 0.
    """
    m, k = mass / NORMAL_LOAD, stiffness / NORMAL_LOAD
    # with a cut-off, psi's derivative in ln(theta) at the steady state: b vc / (vc + V)
    effect = law.b if law.cutoff_speed is None else (
        law.b * law.cutoff_speed / (law.cutoff_speed + speed))
    return np.roots([m * law.dc, m * speed + law.a * law.dc / speed,
                     law.a - effect + k * law.dc, k * speed])


def _oscillation_growth(stiffness: float, law: RateState, mass: float, speed: float) -> float:
    """The ratio of the spring force's swing in the last tenth of a run to the first's."""
    bench = SpringSlider(mass=mass, stiffness=stiffness, drive_speed=speed,
                         normal_load=NORMAL_LOAD)
    steady = float(steady_friction(law, speed))
    mode = max(_linear_modes(stiffness, law, mass, speed), key=lambda root: root.imag)
    period = 2 * np.pi / mode.imag
    duration = max(12 * period, 2.5 / abs(mode.real))  # long enough to grow or decay e^2
    ds = simulate_spring_slider(bench, law, duration=duration, sample_rate=100 / period,
                                initial_ratio=steady - 1e-5)
    swing = np.abs(ds.friction_ratio.values - steady)
    tenth = swing.size // 10
    return float(swing[-tenth:].max() / swing[:tenth].max())


@pytest.mark.parametrize("evolution", ["aging", "slip"])
@pytest.mark.parametrize(("mass", "speed"), [(0.0, 1e-5), (MASS, 3.1e-4)])
def test_steady_sliding_loses_stability_at_the_critical_stiffness(
        evolution: str, mass: float, speed: float) -> None:
    # K_c = N (b - a) / Dc (1 + M V^2 / (N a Dc)): 1505 N/m quasi-static; at 0.31 mm/s
    # the Colas slider's inertia doubles it (2980 N/m)
    law = RateState(a=0.01, b=0.015, dc=1e-6, mu0=0.4, evolution=evolution)  # type: ignore[arg-type]
    critical = critical_stiffness(law, NORMAL_LOAD, mass=mass, drive_speed=speed)
    assert max(_linear_modes(0.999 * critical, law, mass, speed).real) > 0
    assert max(_linear_modes(1.001 * critical, law, mass, speed).real) < 0
    assert _oscillation_growth(0.9 * critical, law, mass, speed) > 3.0
    assert _oscillation_growth(1.1 * critical, law, mass, speed) < 1 / 3.0


@pytest.mark.parametrize(("mass", "speed"), [(0.0, 1e-5), (MASS, 3.1e-4)])
def test_a_cutoff_moves_the_critical_stiffness_where_the_simulation_sees_it(
        mass: float, speed: float) -> None:
    # the cut-off at 0.3 mm/s takes 3 % of b's effect at 10 um/s and half at 0.31 mm/s
    law = RateState(a=0.01, b=0.03, dc=1e-6, mu0=0.4, cutoff_speed=3e-4)
    critical = critical_stiffness(law, NORMAL_LOAD, mass=mass, drive_speed=speed)
    uncut = critical_stiffness(RateState(a=0.01, b=0.03, dc=1e-6, mu0=0.4), NORMAL_LOAD,
                               mass=mass, drive_speed=speed)
    assert critical < 0.97 * uncut
    assert _oscillation_growth(0.9 * critical, law, mass, speed) > 3.0
    assert _oscillation_growth(1.1 * critical, law, mass, speed) < 1 / 3.0


def test_a_cutoff_spends_the_state_effect_above_its_speed() -> None:
    cut = RateState(a=0.01, b=0.015, dc=2e-6, mu0=0.4, cutoff_speed=1e-3)
    uncut = RateState(a=0.01, b=0.015, dc=2e-6, mu0=0.4)
    far = RateState(a=0.01, b=0.015, dc=2e-6, mu0=0.4, cutoff_speed=1e6)
    speed, log_state = np.geomspace(1e-9, 1.0, 7), np.linspace(-8.0, 6.0, 7)
    # a cut-off far above every speed is no cut-off
    np.testing.assert_allclose(friction(far, speed, log_state),
                               friction(uncut, speed, log_state), rtol=1e-9)
    # the law and its inverse agree with a cut-off
    mu = friction(cut, speed, log_state)
    np.testing.assert_allclose(slip_rate(cut, mu, log_state), speed, rtol=1e-9)
    # steady friction's slope in ln(v): a - b well below vc, a well above it
    def slope(v: float) -> float:
        return float(np.diff(steady_friction(cut, [v, v * 1.01]))[0] / np.log(1.01))
    assert slope(1e-7) == pytest.approx(0.01 - 0.015, rel=1e-3)
    assert slope(1.0) == pytest.approx(0.01, rel=2e-3)
    assert slope(1e-3) == pytest.approx(0.01 - 0.015 / 2, rel=1e-2)
    with pytest.raises(SlipwaveError, match="cut-off speed"):
        RateState(a=0.01, b=0.015, dc=2e-6, mu0=0.4, cutoff_speed=0.0)


def test_a_soft_spring_sticks_and_slips() -> None:
    law = RateState(a=0.01, b=0.02, dc=1e-6, mu0=0.35)
    bench = SpringSlider(mass=MASS, stiffness=168.0, drive_speed=42e-6, normal_load=NORMAL_LOAD)
    ds = simulate_spring_slider(bench, law, duration=20.0, sample_rate=2000.0,
                                initial_ratio=float(steady_friction(law, 42e-6)) - 1e-3)
    late = ds.sel(time=slice(10.0, None))
    stuck = late.slider_speed < 0.1 * bench.drive_speed
    assert 0.5 < float(stuck.mean()) < 1.0  # most of the time stuck, but not all
    assert float(late.slider_speed.max()) > 100 * bench.drive_speed  # slips are fast
    # stuck, the spring loads at K V / N
    rise = np.gradient(late.friction_ratio.values, late.time.values)[stuck.values]
    assert np.median(rise) == pytest.approx(168.0 * 42e-6 / NORMAL_LOAD, rel=0.02)
    # the slider moved as far as the drive, less what the spring took up
    slip = ds.drive_displacement - NORMAL_LOAD / 168.0 * (ds.friction_ratio - ds.friction_ratio[0])
    np.testing.assert_allclose(ds.slip, slip)


def test_an_integration_past_its_budget_stops_with_the_reason() -> None:
    law = RateState(a=0.01, b=0.02, dc=1e-6, mu0=0.35)
    bench = SpringSlider(mass=MASS, stiffness=168.0, drive_speed=42e-6, normal_load=NORMAL_LOAD)
    run = {"duration": 4.0, "sample_rate": 2000.0, "initial_ratio": 0.33}
    free = simulate_spring_slider(bench, law, **run)  # type: ignore[arg-type]
    within = simulate_spring_slider(bench, law, max_evaluations=10**7, **run)  # type: ignore[arg-type]
    np.testing.assert_array_equal(within.friction_ratio, free.friction_ratio)
    with pytest.raises(SlipwaveError, match="used its 500 evaluations"):
        simulate_spring_slider(bench, law, max_evaluations=500, **run)  # type: ignore[arg-type]


@pytest.mark.parametrize("law", [
    RateState(a=0.006, b=0.009, dc=3e-7, mu0=0.35),
    RateState(a=0.006, b=0.009, dc=3e-7, mu0=0.35, b2=-0.004, dc2=3e-5),
    RateState(a=0.006, b=0.009, dc=3e-7, mu0=0.35, b2=0.003, dc2=3e-5, evolution="slip"),
    RateState(a=0.006, b=0.009, dc=3e-7, mu0=0.35, cutoff_speed=1e-4),
    RateState(a=0.006, b=0.009, dc=3e-7, mu0=0.35, b2=-0.004, dc2=3e-5, cutoff_speed=1e-3),
])
def test_the_inertial_jacobian_is_the_right_hand_side_s(law: RateState) -> None:
    """The analytic Jacobian against central differences, in a stick and in a slip."""
    bench = SpringSlider(mass=MASS, stiffness=1002.0, drive_speed=42e-6, normal_load=NORMAL_LOAD)
    rhs, jacobian = _inertial(bench, law, 42e-6)
    count = 1 if law.dc2 is None else 2
    for state in ([0.36, 0.01] + [np.log(3e-7 / 1e-4)] * count,   # slipping at 0.1 mm/s
                  [0.34, -0.02] + [np.log(1e-2) + 0.3] * count):  # slowing down
        y = np.array(state)
        steps = 1e-7 * np.maximum(1.0, np.abs(y))
        differences = np.column_stack([
            (rhs(0.0, y + step * unit) - rhs(0.0, y - step * unit)) / (2 * step)
            for step, unit in zip(steps, np.eye(y.size), strict=True)])
        np.testing.assert_allclose(jacobian(0.0, y), differences, rtol=0,
                                   atol=1e-7 * np.abs(differences).max())


def test_an_idle_second_state_changes_no_stick_slip() -> None:
    """A second state with b2 = 0 leaves the inertial slider's saw-tooth as it was."""
    bench = SpringSlider(mass=MASS, stiffness=168.0, drive_speed=42e-6, normal_load=NORMAL_LOAD)
    records = [simulate_spring_slider(bench, law, duration=8.0, sample_rate=2000.0,
                                      initial_ratio=0.33)
               for law in (RateState(a=0.01, b=0.02, dc=1e-6, mu0=0.35),
                           RateState(a=0.01, b=0.02, dc=1e-6, mu0=0.35, b2=0.0, dc2=3e-5))]
    assert float(records[0].friction_ratio.max() - records[0].friction_ratio.min()) > 0.02
    np.testing.assert_allclose(records[1].friction_ratio, records[0].friction_ratio,
                               atol=1e-6)
    assert "log_state_2" in records[1] and "log_state_2" not in records[0]


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"a": 0.0, "b": 0.01, "dc": 1e-6, "mu0": 0.4}, "a > 0"),
    ({"a": 0.01, "b": 0.01, "dc": -1.0, "mu0": 0.4}, "dc > 0"),
    ({"a": 0.01, "b": 0.01, "dc": 1e-6, "mu0": 0.4, "evolution": "nagata"}, "nagata"),
])
def test_bad_laws_are_refused(kwargs: dict[str, object], message: str) -> None:
    with pytest.raises(SlipwaveError, match=message):
        RateState(**kwargs)  # type: ignore[arg-type]


def test_bad_benches_are_refused() -> None:
    with pytest.raises(SlipwaveError, match="stiffness > 0"):
        SpringSlider(mass=0.03, stiffness=0.0, drive_speed=1e-5, normal_load=0.3)
    bench = SpringSlider(mass=0.03, stiffness=100.0, drive_speed=1e-5, normal_load=0.3)
    law = RateState(a=0.01, b=0.015, dc=1e-6, mu0=0.4)
    with pytest.raises(SlipwaveError, match="drive speed must be >= 0"):
        simulate_spring_slider(bench, law, duration=1.0, sample_rate=10.0,
                               speed_steps=[(0.5, -1e-5)])


def test_leaving_out_inertia_in_creep_changes_nothing_measurable() -> None:
    """Below INERTIA_SPEED_FRACTION of the drive the slider is taken as massless; the whole
    record, integrated with inertia throughout by Radau at tight tolerances, agrees."""
    from scipy.integrate import solve_ivp

    from slipwave.solver import spring_slider

    law = RateState(a=0.01, b=0.02, dc=1e-6, mu0=0.35)
    bench = SpringSlider(mass=MASS, stiffness=168.0, drive_speed=1.1e-3, normal_load=NORMAL_LOAD)
    start = float(steady_friction(law, 1.1e-3)) - 1e-3
    ds = simulate_spring_slider(bench, law, duration=1.0, sample_rate=2000.0, initial_ratio=start)
    rhs, jacobian = spring_slider._inertial(bench, law, 1.1e-3)
    whole = solve_ivp(rhs, (0.0, 1.0), [start, 0.0, np.log(law.dc / 1.1e-3)], method="Radau",
                      jac=jacobian, t_eval=ds.time.values, rtol=1e-10, atol=[1e-12, 1e-14, 1e-12])
    assert whole.status == 0
    assert (ds.slider_speed < 1e-3 * bench.drive_speed).any()  # it did stick
    np.testing.assert_allclose(ds.friction_ratio, whole.y[0], rtol=0, atol=1e-4)

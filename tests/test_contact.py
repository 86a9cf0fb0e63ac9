"""Contact laws: force formulas, Hertz single impact, gradients, `make_law` and its validation."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import hertz_chain as hc
from hertz_chain import calibration
from hertz_chain.calibration import HERTZ_CONTACT_TIME_FACTOR, hertz_impact
from hertz_chain.contact import (
    LAW_NAMES,
    Hertz,
    HuntCrossley,
    HertzDashpot,
    KelvinVoigt,
    PowerLaw,
    Thornton,
    Tsuji,
    Viscoelastic,
    make_law,
)
from hertz_chain.errors import ParameterError


def _hertz_impact_scipy(m, k, v):
    """Dimensional elastic Hertz impact m d'' = -k d^{3/2}, DOP853 rtol 1e-13 (independent method)."""
    d_scale = (m * v * v / k) ** 0.4

    def rhs(t, y):
        return [y[1], -k * max(y[0], 0.0) ** 1.5 / m]

    def ev_zero(t, y):
        return y[0]

    ev_zero.terminal, ev_zero.direction = True, -1

    def ev_top(t, y):
        return y[1]

    ev_top.direction = -1
    sol = solve_ivp(rhs, (0, 100 * d_scale / v), [0.0, v], method="DOP853", rtol=1e-13,
                    atol=[1e-16 * d_scale, 1e-16 * v], events=[ev_zero, ev_top])
    d_max = sol.y_events[1][0][0]
    return d_max, sol.t_events[0][0], k * d_max**1.5, -sol.y_events[0][0][1] / v


@pytest.mark.parametrize("m, k, v", [(0.1, 1e9, 1.0), (2.5, 3.7e10, 0.3), (1e-3, 5e7, 7.0)])
def test_hertz_single_impact_closed_form(m, k, v):
    # Johnson (1985) Contact Mechanics §11.4; docs/references.md: delta_max = (5 m v^2/(4k))^{2/5},
    # t_c = 2.94328 delta_max / v, F_max = k delta_max^{3/2}. Checked against scipy to 1e-7 (relative).
    d_max, t_c, f_max, e = _hertz_impact_scipy(m, k, v)
    d_ref = (5 * m * v * v / (4 * k)) ** 0.4
    assert d_max == pytest.approx(d_ref, rel=1e-7)
    # 2.94328 and 3.21807 are printed to 6 digits: half a unit of the last digit is 1.7e-6 relative
    assert t_c == pytest.approx(2.94328 * d_ref / v, rel=1.7e-6)
    assert t_c == pytest.approx(HERTZ_CONTACT_TIME_FACTOR * d_ref / v, rel=1e-7)
    assert t_c == pytest.approx(3.21807 * (m / k) ** 0.4 * v**-0.2, rel=1.6e-6)  # docs/references.md
    assert f_max == pytest.approx(k * d_ref**1.5, rel=1e-7)
    assert e == pytest.approx(1.0, abs=1e-9)  # elastic
    closed = hertz_impact(m, k, v)
    assert closed["max_overlap"] == pytest.approx(d_max, rel=1e-7)
    assert closed["contact_time"] == pytest.approx(t_c, rel=1e-7)
    assert closed["max_force"] == pytest.approx(f_max, rel=1e-7)


def test_hertz_contact_time_factor_value():
    # (4/5) B(2/5, 1/2) = 2.943275..., printed as 2.94328 in docs/references.md (Johnson 1985 §11.4).
    assert HERTZ_CONTACT_TIME_FACTOR == pytest.approx(2.94328, abs=5e-6)


D, DD = 2.0e-4, 0.7  # a compressed state: overlap (m) and its rate (m/s)


@pytest.mark.parametrize(
    "law, expected",
    [
        # each expected value is the published formula written out in NumPy
        (Hertz(3e9), 3e9 * D**1.5),  # Hertz 1882
        (HuntCrossley(3e9, 0.4), 3e9 * D**1.5 * (1 + 0.4 * DD)),  # Hunt & Crossley 1975
        (Tsuji(3e9, 0.3, 0.2), 3e9 * D**1.5 + 0.3 * math.sqrt(0.2 * 3e9) * D**0.25 * DD),  # Tsuji 1992
        (KelvinVoigt(2e7, 150.0), 2e7 * D + 150.0 * DD),
        (Viscoelastic(3e9, 2e-5), 3e9 * (D**1.5 + 1.5 * 2e-5 * math.sqrt(D) * DD)),  # Brilliantov 1996
    ],
)
def test_force_formulas(law, expected):
    assert float(law.force(D, DD)) == pytest.approx(expected, rel=1e-14)
    assert float(law.force(-1e-6, DD)) == 0.0  # open contact
    assert float(law.force(0.0, DD)) == 0.0  # no force at first touch (delta = 0 is open)


def test_clamp_switch():
    # strong rebound velocity: the raw damped force is tensile; the clamp sets it to 0
    law = Tsuji(3e9, 0.8, 0.2)
    raw = 3e9 * D**1.5 + 0.8 * math.sqrt(0.2 * 3e9) * D**0.25 * (-5.0)
    assert raw < 0
    assert float(law.force(D, -5.0)) == 0.0
    assert float(Tsuji(3e9, 0.8, 0.2, clamp=False).force(D, -5.0)) == pytest.approx(raw, rel=1e-14)


def test_names():
    # every law of the registry is public under its class name, in hertz_chain and hertz_chain.contact (a
    # review added a law: hc.NewLaw was an AttributeError); the names in the registry's order
    from hertz_chain import contact as hc_contact
    from hertz_chain import registry

    for name, row in registry.LAWS.items():
        cls = getattr(hc, row.cls)
        assert cls is getattr(hc_contact, row.cls) and row.cls in hc_contact.__all__ and row.cls in hc.__all__
        assert cls.name == name
    assert list(LAW_NAMES) == list(registry.LAWS)
    assert Hertz.name == "hertz" and Tsuji.name == "tsuji" and Thornton.name == "thornton"


@pytest.mark.parametrize("p", [1.2, 2.0])
def test_power_law_contact_time_and_restitution(p):
    """F = k delta^p: the elastic impact lasts t_c = (2/(p+1)) B(1/(p+1), 1/2) delta_m / v with
    delta_m = ((p+1) m v^2 / (2k))^(1/(p+1)) (energy integral, written out here); with Hunt–Crossley damping
    of the same exponent the restitution is the exact map e(chi = alpha v), for any p (Carvalho & Martins
    2019), measured by the simulator at two speeds."""
    from scipy.special import beta

    m, k, v = 0.2, 1e8, 1.3
    d_m = ((p + 1) * m * v**2 / (2 * k)) ** (1 / (p + 1))
    t_c = 2 / (p + 1) * beta(1 / (p + 1), 0.5) * d_m / v
    res = hc.simulate_impact(PowerLaw(k, p), v, m, tolerances=hc.Tolerances(rtol=1e-11, atol=1e-11))
    assert res.e == pytest.approx(1.0, abs=1e-9)
    assert res.contact_time == pytest.approx(t_c, rel=1e-7)
    assert res.max_overlap == pytest.approx(d_m, rel=1e-8)
    law = make_law("power", stiffness=k, exponent=p, restitution=0.7, calibration_velocity=1.0)
    for speed in (1.0, 2.5):
        e = hc.simulate_impact(law, speed, m, tolerances=hc.Tolerances(rtol=1e-11, atol=1e-11)).e
        assert e == pytest.approx(float(calibration.hunt_crossley_restitution(float(law.alpha), speed)), abs=1e-8)
    assert float(law.restitution_at(1.0)) == pytest.approx(0.7, abs=1e-10)


@pytest.mark.parametrize("v", [0.5, 1.0, 2.0])
def test_hertz_dashpot_restitution_against_a_dimensional_scipy_impact(v):
    """Hertz with a linear dashpot (Rosas et al. 2007), calibrated to e = 0.7 at 1 m/s: an independent
    dimensional DOP853 integration of m* d'' = -(k d^{3/2} + gamma d')_+ from first touch, ended where the
    force vanishes (clamp), gives the law's restitution at 0.5, 1 and 2 m/s (rising with the speed), and
    0.7 at the calibration speed."""
    m, k = 0.2, 1e9
    law = make_law("hertz-dashpot", stiffness=k, restitution=0.7, effective_mass=m, calibration_velocity=1.0)
    gamma = float(law.gamma)

    def force(d, r):
        return k * max(d, 0.0) ** 1.5 + gamma * r

    def ev(t, y):
        return force(y[0], y[1])

    ev.terminal, ev.direction = True, -1
    t_c = 3.21807 * (m / k) ** 0.4 * v**-0.2
    sol = solve_ivp(lambda t, y: (y[1], -max(force(y[0], y[1]), 0.0) / m), (0.0, 10 * t_c), [0.0, v],
                    method="DOP853", rtol=1e-12, atol=1e-15 * v, events=ev)
    e = -sol.y_events[0][0][1] / v
    assert float(law.restitution_at(v, m)) == pytest.approx(e, abs=1e-8)
    if v == 1.0:
        assert e == pytest.approx(0.7, abs=1e-8)


ALL_LAWS = [
    Hertz(3e9), HuntCrossley(3e9, 0.4), Tsuji(3e9, 0.3, 0.2), KelvinVoigt(2e7, 150.0),
    Viscoelastic(3e9, 2e-5), Tsuji(3e9, 0.3, 0.2, clamp=False), Viscoelastic(3e9, 2e-5, clamp=False),
]


@pytest.mark.parametrize("law", ALL_LAWS, ids=lambda l: f"{l.name}-{l.clamp}")
def test_gradient_in_delta_is_finite_at_and_below_contact(law):
    # double-where masking (jax-md): fractional powers must not give NaN/inf gradients at delta <= 0
    g = jax.grad(law.force, argnums=(0, 1))
    for d in (0.0, -1e-5):
        gd, gv = g(jnp.asarray(d), jnp.asarray(0.5))
        assert np.isfinite(gd) and np.isfinite(gv)
        assert float(gd) == 0.0 and float(gv) == 0.0
    gd, _ = g(jnp.asarray(D), jnp.asarray(DD))
    assert np.isfinite(gd) and float(gd) > 0


@pytest.mark.parametrize("law", ALL_LAWS, ids=lambda l: f"{l.name}-{l.clamp}")
def test_gradient_in_stiffness_matches_finite_differences(law):
    # central finite differences, step 1e-6 relative: truncation ~1e-12, rounding ~1e-10
    def f(k):
        return eqx_replace_k(law, k).force(D, DD)

    k0 = float(law.k)
    grad = float(jax.grad(f)(jnp.asarray(k0)))
    h = 1e-6 * k0
    fd = (float(f(k0 + h)) - float(f(k0 - h))) / (2 * h)
    assert grad == pytest.approx(fd, rel=1e-7)


def eqx_replace_k(law, k):
    import equinox as eqx

    return eqx.tree_at(lambda l: l.k, law, k)


def test_vmap_over_stiffness():
    ks = jnp.array([1e9, 2e9, 4e9])
    f = jax.vmap(lambda k: Hertz(k).force(D, DD))(ks)
    np.testing.assert_allclose(f, np.array([1e9, 2e9, 4e9]) * D**1.5, rtol=1e-14)


# ------------------------------------------------------------------------------------------ make_law


def test_make_law_builds_each_law():
    k = 3e9
    assert isinstance(make_law("hertz", stiffness=k), Hertz)
    assert isinstance(make_law("hertz", stiffness=k, restitution=1.0), Hertz)
    hc = make_law("hunt-crossley", stiffness=k, alpha=0.25, clamp=False)
    assert isinstance(hc, HuntCrossley) and float(hc.alpha) == 0.25 and hc.clamp is False
    hc = make_law("hunt-crossley", stiffness=k, restitution=0.5, calibration_velocity=2.0,
                  chi_map="hunt-crossley")
    assert float(hc.alpha) == pytest.approx(1.5 * 0.5 / 2.0, rel=1e-15)  # chi = 3(1-e)/2, Hunt & Crossley 1975
    ts = make_law("tsuji", stiffness=k, damping=0.3, effective_mass=0.2)
    assert float(ts.eta) == 0.3 and float(ts.m_eff) == 0.2
    assert float(make_law("tsuji", stiffness=k, eta=0.3, effective_mass=0.2).eta) == 0.3
    kv = make_law("kelvin-voigt", stiffness=2e7, restitution=0.5, effective_mass=0.2, clamp=False)
    # unclamped: c = 2 zeta sqrt(m k), zeta = -ln e / sqrt(pi^2 + ln^2 e) (exact, damped oscillator)
    zeta = -math.log(0.5) / math.sqrt(math.pi**2 + math.log(0.5) ** 2)
    assert float(kv.c) == pytest.approx(2 * zeta * math.sqrt(0.2 * 2e7), rel=1e-14)
    ve = make_law("viscoelastic", stiffness=k, A=1e-5)
    assert float(ve.A) == 1e-5
    assert float(make_law("viscoelastic", stiffness=k, damping=1e-5).A) == 1e-5


def test_make_law_restitution_round_trip():
    # each law reproduces its target at the calibration velocity (clamped, the default)
    for law in (
        make_law("hunt-crossley", stiffness=3e9, restitution=0.7, calibration_velocity=1.5),
        make_law("tsuji", stiffness=3e9, restitution=0.7, effective_mass=0.2),
        make_law("kelvin-voigt", stiffness=2e7, restitution=0.7, effective_mass=0.2),
        make_law("viscoelastic", stiffness=3e9, restitution=0.7, effective_mass=0.2, calibration_velocity=1.5),
    ):
        assert law.restitution_at(1.5, 0.2) == pytest.approx(0.7, abs=1e-9)


def test_hunt_crossley_restitution_falls_with_speed():
    law = make_law("hunt-crossley", stiffness=3e9, restitution=0.8, calibration_velocity=1.0)
    e = law.restitution_at(np.array([0.25, 0.5, 1.0, 2.0, 4.0]))
    assert np.all(np.diff(e) < 0)
    assert e[2] == pytest.approx(0.8, abs=1e-12)


@pytest.mark.parametrize(
    "kwargs, param",
    [
        (dict(name="hertz", stiffness=0.0), "stiffness"),
        (dict(name="hertz", stiffness=-1e9), "stiffness"),
        (dict(name="hertz", stiffness=float("nan")), "stiffness"),
        (dict(name="rubber-band", stiffness=1e9), "law"),
        (dict(name="hunt-crossley", stiffness=1e9, restitution=0.5, calibration_velocity=1.0, chi_map="nope"), "chi_map"),
        (dict(name="hunt-crossley", stiffness=1e9, restitution=0.0, calibration_velocity=1.0), "restitution"),
        (dict(name="hunt-crossley", stiffness=1e9, restitution=1.2, calibration_velocity=1.0), "restitution"),
        (dict(name="tsuji", stiffness=1e9, restitution=-0.3, effective_mass=1.0), "restitution"),
        (dict(name="hunt-crossley", stiffness=1e9, restitution=0.5), "calibration_velocity"),
        (dict(name="hunt-crossley", stiffness=1e9, restitution=0.5, calibration_velocity=0.0), "calibration_velocity"),
        (dict(name="tsuji", stiffness=1e9, restitution=0.5), "effective_mass"),
        (dict(name="tsuji", stiffness=1e9, eta=0.3), "effective_mass"),
        (dict(name="kelvin-voigt", stiffness=1e9, restitution=0.5), "effective_mass"),
        (dict(name="viscoelastic", stiffness=1e9, restitution=0.5, effective_mass=1.0), "calibration_velocity"),
        (dict(name="viscoelastic", stiffness=1e9, restitution=0.5, calibration_velocity=1.0), "effective_mass"),
        (dict(name="hertz", stiffness=1e9, restitution=0.8), "restitution"),
        (dict(name="hertz", stiffness=1e9, alpha=0.1), "alpha"),
        (dict(name="tsuji", stiffness=1e9, alpha=0.1, effective_mass=1.0), "alpha"),
        (dict(name="tsuji", stiffness=1e9, restitution=0.5, eta=0.1, effective_mass=1.0), "eta"),
        (dict(name="tsuji", stiffness=1e9, eta=0.1, damping=0.1, effective_mass=1.0), "damping"),
        (dict(name="kelvin-voigt", stiffness=1e9), "restitution"),
        (dict(name="kelvin-voigt", stiffness=1e9, damping=-1.0), "damping"),
        (dict(name="tsuji", stiffness=1e9, restitution=0.5, effective_mass=1.0, chi_map="flores"), "chi_map"),
    ],
)
def test_make_law_rejects_bad_input(kwargs, param):
    name = kwargs.pop("name")
    with pytest.raises(ParameterError) as info:
        make_law(name, **kwargs)
    assert info.value.name == param
    assert param in str(info.value)


@pytest.mark.parametrize("name, kwargs, param", [
    ("hertz", lambda v: dict(stiffness=v), "stiffness"),
    ("tsuji", lambda v: dict(stiffness=1e9, restitution=v, effective_mass=0.3), "restitution"),
])
def test_make_law_under_a_trace_says_so(name, kwargs, param):
    """`make_law` reads configuration values (floats, calibrations in SciPy): a traced value is refused
    with one line that names the parameter and points at the law classes, not as "invalid: a number";
    the class itself differentiates (Hertz's force k d^1.5: dF/dk = d^1.5)."""
    with pytest.raises(ParameterError, match=rf"{param} = 'a traced value'.*construct the law class"):
        jax.grad(lambda v: make_law(name, **kwargs(v)).force(jnp.asarray(1e-4), jnp.asarray(0.0)))(0.8)
    assert jax.grad(lambda k: hc.Hertz(k).force(jnp.asarray(1e-4), jnp.asarray(0.0)))(1e9) == pytest.approx(1e-6, rel=1e-12)


@pytest.mark.parametrize("build, field", [
    (lambda: Hertz(-1e9), "k"),
    (lambda: Hertz(math.nan), "k"),
    (lambda: Hertz(np.array([1e9, 0.0])), "k"),
    (lambda: HuntCrossley(1e9, -0.1), "alpha"),
    (lambda: Tsuji(1e9, -0.5, 1.0), "eta"),
    (lambda: Tsuji(1e9, 0.5, 0.0), "m_eff"),
    (lambda: KelvinVoigt(1e6, -1.0), "c"),
    (lambda: Viscoelastic(1e9, math.inf), "A"),
    (lambda: HertzDashpot(1e9, -2.0), "gamma"),
    (lambda: PowerLaw(1e9, 0.5), "p"),
    (lambda: hc.Thornton(1e9, -1e-6), "delta_y"),
    (lambda: hc.JacksonGreen(2e10, 0.005, -1e9), "yield_strength"),
])
def test_law_constructors_check_their_numbers(build, field):
    """The classes themselves, not only `make_law` (a review: `Hertz(-1e9)` ran to "no contact" with NaN
    launch velocities, `Hertz(nan)` to 65,536 steps and "raise max_steps", `Tsuji(1e9, -0.5, 1.0)`
    created energy): one ParameterError naming the argument. Traced values are not checked (their
    numbers are unknown), so a law built under `jit` or `vmap` still traces."""
    with pytest.raises(ParameterError, match=rf"^{field} = .* is invalid: .*must be finite and >") as info:
        build()
    assert "\n" not in str(info.value)
    assert float(jax.jit(lambda k: Hertz(k).elastic_force(1e-6))(-1.0)) == pytest.approx(-1e-9, rel=1e-12)


def test_jackson_green_built_directly_has_make_laws_continuous_switch():
    """`JacksonGreen(k, R, S_y)` took `switch = 1.9`, where the published fit starts 0.5 % above Hertz (a
    jump of the loading force); now the switch of `make_law`, where the fit meets Hertz: the loading force
    just above it equals Hertz's k delta^(3/2), written out here, to 1e-9."""
    law = hc.JacksonGreen(2e10, 0.005, 1e9)
    ref = hc.make_law("jackson-green", stiffness=2e10, yield_strength=1e9, effective_radius=0.005)
    assert float(law.switch) == pytest.approx(float(ref.switch), rel=1e-14) and float(law.switch) > 1.9
    _, _, w_c, _ = (float(x) for x in law._scales())
    d = float(law.switch) * w_c * (1 + 1e-12)
    assert float(law.loading_force(d)) == pytest.approx(2e10 * d**1.5, rel=1e-9)
    assert float(hc.JacksonGreen(2e10, 0.005, 1e9, switch=1.9).switch) == 1.9  # as given
    # the same law under the caller's jit (Python numbers are traced there: it took 1.9, a review)
    assert float(jax.jit(lambda: hc.JacksonGreen(2e10, 0.005, 1e9))().switch) == float(law.switch)
    # a bad number is named before the switch is sought (was scipy's "f(a) and f(b) must have different
    # signs"), and a fit that starts below Hertz is refused, as make_law refuses it
    with pytest.raises(ParameterError, match=r"^poisson_ratio = -2.0 is invalid"):
        hc.JacksonGreen(2e10, 0.005, 1e9, -2.0)
    with pytest.raises(ParameterError, match=r"^yield_strength = 5000000000.0 is invalid: a law whose fit meets"):
        hc.JacksonGreen(1e10, 0.01, 5e9)

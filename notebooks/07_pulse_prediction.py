# ---
# jupyter:
#   jupytext:
#     text_representation:
#       extension: .py
#       format_name: percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # 7. Predicting the shock pulse of a real steel stack, against standard shock-test levels
#
# The seed paper designs amplifiers by velocity gain; a shock test is specified by an acceleration
# pulse (half-sine: peak and duration) or by its shock response spectrum (SRS). Here the pulse on the
# top mass (where the device under test sits) is predicted for stacks whose contact stiffness comes
# from materials and geometry (Hertz: `k = (4/3) E* √R*`, `1/E* = (1−ν₁²)/E₁ + (1−ν₂²)/E₂`,
# `1/R* = 1/R₁ + 1/R₂`; Johnson 1985, docs/references.md, "Hertz single impact") and compared with the test conditions of
# MIL-STD-883 Method 2002 and JESD22-B110.
#
# 1. The project's example `examples/steel_materials.toml` (three masses, bearing-steel balls, a
#    stainless flat top, dropped 10 cm on a steel anvil; viscoelastic contacts).
# 2. The paper's six-mass MVG stack (`R = 0.012`, `m_1 = 8.4 kg`, Eq 15) made of AISI 52100 spheres from
#    `data/materials.csv`, on an AISI 4340 anvil, dropped from 1 cm to 1 m — all steel, and with a
#    nylon 66 cap on the top mass (a "pulse programmer").
#
# Findings (asserted below): steel-on-steel contacts give very short pulses (0.04–0.07 ms) — shorter
# than every half-sine duration of both standards (≥ 0.12 ms), so **no condition is met in peak and
# duration**, although the peak levels are reached from drops of a few centimetres and the SRS of the
# short pulse covers that of a condition whenever its velocity change and peak are both larger. A
# nylon cap lengthens the top pulse to 0.18–0.28 ms and the stack then **meets MIL-STD-883 condition E
# (10,000 g, 0.2 ms) for drops of about 0.16–0.33 m**, pulse and SRS. All predictions are elastic:
# the Hertz pressures exceed the yield onset of the materials (see the end), so real contacts will
# flatten plastically, lowering the peaks and lengthening the pulses.

# %%
import time
import warnings

import numpy as np
import jax
import jax.numpy as jnp
import matplotlib.pyplot as plt

from _nbutil import QUICK, repo_root, show, write_table
import hertz_chain as hc
from hertz_chain import calibration, rigid
from hertz_chain.materials import load_materials
from hertz_chain.spectrum import SRSResolutionWarning, octave_frequencies

T0 = time.perf_counter()
G0 = hc.G0
EX = repo_root() / "examples"
FREQ = octave_frequencies(50.0, 1e4, per_octave=6 if QUICK else 12)  # SRS grid, Hz (a usual test band)

# %% [markdown]
# ## Standard shock-test levels (half-sine pulses)
#
# | standard | conditions (peak g / duration ms) | source of the numbers |
# |---|---|---|
# | MIL-STD-883, Method 2002 (mechanical shock, microcircuits) | A 500/1.0, B 1500/0.5, C 3000/0.3, D 5000/0.3, E 10000/0.2, F 20000/0.2, G 30000/0.12 | `docs/references.md, "Test levels"` (secondary sources, marked unverified) |
# | JESD22-B110 (mechanical shock, component and subassembly), service conditions | A 500/1.0, B 1500/0.5, C 100/2.0, D 200/1.5, E 340/1.2, F 900/0.7, G 2000/0.4, H 2900/0.3 | `docs/references.md, "Test levels"` (same); condition B (1500 g, 0.5 ms) also quoted for JESD22-B110B by a secondary web page found with the search tool (dailychipdigest.blogspot.com, 2015) |
#
# Neither standard's own text could be consulted here: **check the levels (and the standards'
# tolerances on peak and duration) against the current revisions before relying on them.** Below, a
# pulse *meets* a condition when its peak is at least the condition's and its equivalent half-sine
# duration (`π ΔV/(2 · peak)`, the half-sine with the same peak and velocity change) is at least the
# condition's: at least as severe in both. Its SRS *covers* the condition's when the maximax SRS
# (Q = 10) is at least the half-sine's at every frequency from 50 Hz to 10 kHz. These are this
# notebook's criteria, not the standards' acceptance tolerances.

# %%
SRC_REF = 'docs/references.md, "Test levels" (secondary sources, unverified)'
LEVELS = [("MIL-STD-883 M2002", c, A, D * 1e-3, SRC_REF) for c, A, D in
          (("A", 500, 1.0), ("B", 1500, 0.5), ("C", 3000, 0.3), ("D", 5000, 0.3), ("E", 10000, 0.2),
           ("F", 20000, 0.2), ("G", 30000, 0.12))]
LEVELS += [("JESD22-B110", c, A, D * 1e-3,
            SRC_REF + ("; B also: dailychipdigest.blogspot.com (2015) for JESD22-B110B" if c == "B" else ""))
           for c, A, D in (("A", 500, 1.0), ("B", 1500, 0.5), ("C", 100, 2.0), ("D", 200, 1.5), ("E", 340, 1.2),
                           ("F", 900, 0.7), ("G", 2000, 0.4), ("H", 2900, 0.3))]


def half_sine(A_g, D, n=4001):
    t = np.linspace(0.0, D, n)
    return t, A_g * np.sin(np.pi * t / D)


def maximax(t, a_g, pulse_end=None):
    with warnings.catch_warnings():
        warnings.simplefilter("error", SRSResolutionWarning)  # the record must resolve every frequency
        return hc.srs(t, a_g, FREQ, pulse_end=pulse_end).maximax


HS_SRS = {(s, c): maximax(*half_sine(A, D)) for s, c, A, D, _ in LEVELS}

# half-sine facts (docs/references.md, "Shock pulses"): Delta V = 2AD/pi, 10 % duration 0.936 D,
# SRS (Q = 10) peaks at about 1.65 A near f_n D = 0.83
tB, aB = half_sine(1500.0, 0.5e-3)
pmB = hc.pulse_metrics(tB, aB * G0)
assert np.isclose(pmB.delta_v, 2 * 1500 * G0 * 0.5e-3 / np.pi, rtol=1e-6)
assert np.isclose(pmB.duration_10, 0.93623 * 0.5e-3, rtol=1e-4)
fine = octave_frequencies(500.0, 5000.0, per_octave=48)
sB = hc.srs(tB, aB, fine).maximax
k = int(np.argmax(sB))
print(f"half-sine SRS peak: {sB[k] / 1500:.3f} A at f D = {fine[k] * 0.5e-3:.3f}")
assert 1.60 < sB[k] / 1500 < 1.70 and 0.75 < fine[k] * 0.5e-3 < 0.90


def judge(peak_g, d_eq, srs_pulse):
    """Per condition: meets (peak and equivalent duration at least the condition's); SRS covers."""
    out = {}
    for s, c, A, D, _ in LEVELS:
        ratio = float(np.min(srs_pulse / HS_SRS[(s, c)]))
        out[(s, c)] = (peak_g >= A and d_eq >= D, ratio >= 1.0, ratio)
    return out


# %% [markdown]
# ## 1. The example file: three steel bodies dropped 10 cm (`examples/steel_materials.toml`)
#
# Masses 1 kg, 0.4 kg (AISI 52100 balls, radii 5 and 3 cm) and a 0.16 kg AISI 304 body with a flat face,
# gaps 2 and 1 mm, on an AISI 1045 anvil; viscoelastic contacts calibrated to `e = 0.85` (0.95 at the
# ground) at the rigid approach speeds. The stiffness of each contact is recomputed here from the
# formulas above, typed in, and must equal what `hertz_chain.builder` made of the file.

# %%
spec = hc.load_stack_file(EX / "steel_materials.toml")
built = hc.build(spec)
MAT = {"52100": (210e9, 0.30), "304": (193e9, 0.29), "1045": (205e9, 0.29)}  # from the file


def k_hertz(mat1, mat2, R1, R2=np.inf):
    (E1, n1), (E2, n2) = MAT[mat1] if isinstance(mat1, str) else mat1, MAT[mat2] if isinstance(mat2, str) else mat2
    E_star = 1 / ((1 - n1**2) / E1 + (1 - n2**2) / E2)
    R_star = 1 / (1 / R1 + (0 if np.isinf(R2) else 1 / R2))
    return 4 / 3 * E_star * np.sqrt(R_star)


k_file = [k_hertz("1045", "52100", 0.05), k_hertz("52100", "52100", 0.05, 0.03), k_hertz("52100", "304", 0.03)]
for j, kj in enumerate(k_file):
    assert np.isclose(float(built.stack.law_of(j).k), kj, rtol=1e-12)  # Johnson 1985 Eqs 4.22-4.23
print("stiffness from materials (N/m^1.5):", [f"{kj:.4e}" for kj in k_file])

sol = hc.simulate(built.stack, built.state, **built.simulate_options)
rep = hc.analyse(sol, nominal_restitution=built.nominal_restitution)
p = rep.top_pulse
v_ff = float(-built.state.velocities[0])
print(f"v_ff = {v_ff:.4f} m/s, G = {rep.top_velocity_gain:.4f} (rigid with measured e: "
      f"{rep.rigid.event_driven_gain:.4f}), regime {rep.regime}")
print(f"top pulse: {p.peak_g:,.0f} g, 10 % duration {p.duration_10 * 1e3:.4f} ms, equivalent half-sine "
      f"{p.equivalent_half_sine_duration * 1e3:.4f} ms, dV {p.delta_v_main:.3f} m/s")
assert rep.regime == "independent" and abs(rep.gain_error("event_driven_gain")) < 1e-3
assert p.n_pulses == 1 and not p.truncated
# momentum: the top mass's velocity change in its (single) contact is its launch speed plus its speed
# just before (v_ff + g t at the contact), to the solver's tolerance
top_eps = [ep for ep in rep.episodes if ep.interface == 2]
assert len(top_eps) == 1
t_hit = top_eps[0].start
assert np.isclose(p.delta_v_main, rep.launch_velocities[-1] + v_ff + G0 * t_hit, rtol=2e-3)


def top_record(report, n):
    """Time and accelerometer reading (g) of the top mass around its contact(s), and the contact end."""
    st = report.solution.steps
    eps = [ep for ep in report.episodes if ep.interface == n - 1]
    t0, t1 = min(ep.start for ep in eps), max(ep.end for ep in eps)
    pad = 0.05 * (t1 - t0)
    keep = (st.t >= t0 - pad) & (st.t <= t1 + pad)
    a_g = (st.accelerations[keep, -1] + float(report.solution.stack.gravity)) / G0
    return st.t[keep], a_g, t1


t_ex, a_ex, end_ex = top_record(rep, 3)
srs_ex = maximax(t_ex, a_ex, pulse_end=end_ex)
v_ex = judge(p.peak_g, p.equivalent_half_sine_duration, srs_ex)
met_ex = [f"{s} {c}" for (s, c), (m, _, _) in v_ex.items() if m]
cov_ex = [f"{s} {c}" for (s, c), (_, cv, _) in v_ex.items() if cv]
print("meets:", met_ex or "none", "| SRS covers:", cov_ex)
assert not met_ex  # 0.062 ms: shorter than every condition
assert p.peak_g > 10000  # but above MIL-STD-883 E's peak
# the SRS covers the conditions whose velocity change (2AD/pi) and peak are both below the pulse's
dv_cond = {(s, c): 2 * A * G0 * D / np.pi for s, c, A, D, _ in LEVELS}
for (s, c), (_, cv, ratio) in v_ex.items():
    A = next(L[2] for L in LEVELS if L[:2] == (s, c))
    if dv_cond[(s, c)] < 0.97 * p.delta_v_main and A < p.peak_g:
        assert cv, (s, c, ratio)
    if dv_cond[(s, c)] > 1.03 * p.delta_v_main:
        assert not cv, (s, c, ratio)
print("SRS ratio min (pulse / half-sine):", {f"{s[:4]} {c}": round(r, 2) for (s, c), (_, _, r) in v_ex.items()})

# %% [markdown]
# The example stack's top pulse (about 12,000 g for 0.062 ms, ΔV 4.65 m/s) reaches MIL-STD-883
# condition E's peak from a 10 cm drop but lasts a third of its duration, so it meets no condition.
# Its SRS covers every condition whose half-sine velocity change `2AD/π` is below 4.65 m/s — MIL A
# (3.1 m/s) and JESD A, C, D, E, F — and misses MIL B / JESD B (4.68 m/s) by 1 % at low frequency; the
# SRS at low frequencies is set by the velocity change alone (impulse asymptote).

# %%
fig, axs = plt.subplots(1, 2, figsize=(12, 4.2))
axs[0].plot((t_ex - t_ex[0]) * 1e3, a_ex, "k", lw=1.2, label="predicted top pulse")
tE, aE = half_sine(10000, 0.2e-3)
axs[0].plot(tE * 1e3 + 0.0, aE, "C3--", lw=1, label="MIL-STD-883 E half-sine (10,000 g, 0.2 ms)")
axs[0].set(xlabel="t (ms, from the start of the record)", ylabel="acceleration (g)",
           title="examples/steel_materials.toml: top-mass pulse (no paper figure)")
axs[0].legend(fontsize=8)
axs[1].loglog(FREQ, srs_ex, "k", lw=1.5, label=f"predicted pulse: {p.peak_g:,.0f} g, {p.duration_10 * 1e3:.3f} ms")
for (s, c), col in ((("MIL-STD-883 M2002", "A"), "C0"), (("MIL-STD-883 M2002", "B"), "C1"), (("MIL-STD-883 M2002", "E"), "C3")):
    axs[1].loglog(FREQ, HS_SRS[(s, c)], "--", color=col, lw=1, label=f"{s} {c} half-sine")
axs[1].set(xlabel="natural frequency (Hz)", ylabel="maximax SRS, Q = 10 (g)", title="SRS against test conditions (no paper figure)")
axs[1].legend(fontsize=7)
show(fig, "pulse_example_file_srs")

# %% [markdown]
# ## 2. The paper's six-mass MVG stack in bearing steel, 1 cm to 1 m drops
#
# Masses from Eq 15 (`R = 0.012`, `m_1 = 8.4 kg`: 8.4 … 0.1008 kg), each an AISI 52100 sphere
# (`data/materials.csv`: `steel-52100`, E = 210 GPa, ν = 0.30, ρ = 7810 kg/m³, indicative `e = 0.90`)
# of the radius its mass needs; the anvil is `steel-4340`. Every contact is viscoelastic with `e = 0.9`
# at the rigid approach speeds of a 10 cm drop (so `e` varies with the drop height as the law says).
# Variant "nylon cap": the top mass's lower face is nylon 66 (`nylon-66`, E = 2.9 GPa, ν = 0.40,
# indicative `e = 0.75`), same radius. Gaps 2 mm, gravity on, all drops in one vmapped batch.

# %%
rows_mat = list(load_materials().values())
assert all(mat.source.strip() for mat in rows_mat)  # every row of data/materials.csv names its source
steel, anvil, nylon = hc.material("steel-52100"), hc.material("steel-4340"), hc.material("nylon-66")
R0, M1, N = 0.012, 8.4, 6
m = rigid.mvg_masses(R0, N, M1)
radius = (3 * m / (4 * np.pi * steel.density)) ** (1 / 3)
assert np.allclose([hc.materials.sphere_mass(r, "steel-52100") for r in radius], m, rtol=1e-12)
m_eff = np.concatenate([[m[0]], m[:-1] * m[1:] / (m[:-1] + m[1:])])
GAP = 2e-3
H_REF = 0.10


def variant(top):
    mats = [steel] * (N - 1) + [top]
    ks = np.array([hc.contact_stiffness(anvil, mats[0], radius[0], None)]
                  + [hc.contact_stiffness(mats[j - 1], mats[j], radius[j - 1], radius[j]) for j in range(1, N)])
    es = np.array([steel.typical_restitution] * (N - 1) + [top.typical_restitution])
    hit, _ = rigid.cascade_velocities(m, es, ground_restitution=es[0])
    u_unit = np.concatenate([[1.0], hit[:-1] + 1.0])  # rigid approach speeds per unit v_ff (Eqs 1-2)
    v_ref = np.sqrt(2 * G0 * H_REF)
    laws = [hc.make_law("viscoelastic", stiffness=float(k), restitution=float(e), effective_mass=float(me),
                        calibration_velocity=float(u * v_ref)) for k, e, me, u in zip(ks, es, m_eff, u_unit)]
    return hc.Stack(m, laws), ks, es, u_unit


stacks = {"steel": variant(steel), "nylon cap": variant(nylon)}
# the stiffness, typed in (Johnson): sphere-sphere and sphere-flat
ks_typed = [k_hertz((anvil.youngs_modulus, anvil.poisson_ratio), (steel.youngs_modulus, steel.poisson_ratio), radius[0])]
ks_typed += [k_hertz((steel.youngs_modulus, steel.poisson_ratio), (steel.youngs_modulus, steel.poisson_ratio),
                     radius[j - 1], radius[j]) for j in range(1, N)]
assert np.allclose(stacks["steel"][1], ks_typed, rtol=1e-12)
print("radii (mm):", np.round(radius * 1e3, 2))
print("k steel (N/m^1.5):", [f"{k:.3e}" for k in stacks["steel"][1]], " top nylon:", f"{stacks['nylon cap'][1][-1]:.3e}")

heights = np.array([0.01, 0.05, 0.2, 1.0]) if QUICK else np.unique(np.r_[np.geomspace(0.01, 1.0, 13), 0.2])


def gap_pi(ks, u_unit, v):
    """Notebook 5's design rule: Pi = min_j gap / (t_c,j-1 u_j), with Hertz contact times; and a time
    by which the cascade is over (twice the rigid flight times across the gaps plus the contact times)."""
    u = u_unit * v
    tc = np.array([calibration.hertz_impact(me, k, uj)["contact_time"] for me, k, uj in zip(m_eff, ks, u)])
    return GAP / np.max(tc[:-1] * u[1:]), 2 * (np.sum(GAP / u[1:]) + np.sum(tc))


designs = [(name, h) for name in stacks for h in heights]
for name, h in designs:
    _, ks, es, uu = stacks[name]
    pi, _ = gap_pi(ks, uu, np.sqrt(2 * G0 * h))
    assert pi > 0.6  # sequential contacts (notebook 5's rule)
# with gravity mass 1 keeps bouncing: the solve stops by itself once the first cascade is over
S = hc.stack_designs([stacks[name][0] for name, _ in designs])
X = jax.tree.map(lambda *a: jnp.stack(a), *[hc.dropped(stacks[name][0], h, GAP) for name, h in designs])
t = time.perf_counter()
bs = hc.simulate_batch(S, X, tolerances=hc.Tolerances(rtol=1e-9, atol=1e-9), max_steps=8192)
print(f"{len(designs)} drops in one batch: {time.perf_counter() - t:.1f} s; status {sorted(set(bs.status))}")
assert bs.ok.all()

# %% [markdown]
# ### Pulse metrics against drop height, and the Hertz closed-form estimate
#
# For each drop the top pulse is read from the `Report` (`analyse`). An estimate needs no simulation:
# the top contact is an isolated Hertz impact at the rigid approach speed `u_top` (Eqs 1–2) with the
# pair's reduced mass `m*`, so `peak ≈ k δ_max^{3/2}/m_n` and the equivalent half-sine duration
# `≈ π ΔV/(2 peak)` with `ΔV = (1 + e) u_top m*/m_n` (docs/references.md, "Hertz single impact" closed forms, nominal `e`). It
# gives the simulated peak to within 1–28 % (it ignores the damping, which lowers the peak more at
# high speed) and the duration to within 4–14 %; the simulated pulses follow the Hertz scaling
# `peak ∝ v^{6/5} ∝ h^{0.6}`, `duration ∝ h^{-0.1}` (fitted: `h^{0.56}`, `h^{-0.095}`: the viscoelastic
# `e` falls with speed). The top mass's velocity change is checked exactly against the momentum of its
# contact, `(1 + e_eff) u m*/m_n`.

# %%
rows_b, res = [], {}
for i, (name, h) in enumerate(designs):
    r = hc.analyse(bs.design(i))
    pm = r.top_pulse
    tt, aa, tend = top_record(r, N)
    s_p = maximax(tt, aa, pulse_end=tend)
    _, ks, es, uu = stacks[name]
    v = float(np.sqrt(2 * G0 * h))
    hz = calibration.hertz_impact(m_eff[-1], ks[-1], uu[-1] * v)
    peak_est = hz["max_force"] / m[-1] / G0
    dv_est = (1 + es[-1]) * uu[-1] * v * m_eff[-1] / m[-1]
    deq_est = np.pi * dv_est / (2 * peak_est * G0)
    E_top = 1 / (steel.plane_strain_compliance + (steel if name == "steel" else nylon).plane_strain_compliance)
    R_top = radius[-2] * radius[-1] / (radius[-2] + radius[-1])
    F = pm.peak * m[-1]
    p0 = (6 * F * E_top**2 / (np.pi**3 * R_top**2)) ** (1 / 3)  # Hertz peak pressure (Johnson 1985)
    res[(name, h)] = dict(report=r, pm=pm, srs=s_p, peak_est=peak_est, deq_est=deq_est, p0=p0)
    rows_b.append((name, h, v, r.top_velocity_gain, pm.peak_g, pm.duration_10, pm.equivalent_half_sine_duration,
                   pm.delta_v_main, peak_est, deq_est, p0 / 1e9))
    assert r.regime == "independent" and pm.n_pulses == 1
    ep = [e_ for e_ in r.episodes if e_.interface == N - 1][0]
    me_top = m_eff[-1]  # impulse of the top contact / m_n = (1 + e_eff) u m*/m_n (momentum, any law)
    assert np.isclose(pm.delta_v_main, (1 + ep.restitution) * ep.approach_velocity * me_top / m[-1], rtol=1e-3)
    assert abs(pm.peak_g / peak_est - 1) < 0.3 and abs(pm.equivalent_half_sine_duration / deq_est - 1) < 0.2
    print(f"{name:9s} h = {h:6.3f} m  G = {r.top_velocity_gain:.3f}  {pm.peak_g:9,.0f} g  D10 = {pm.duration_10 * 1e3:.4f} ms"
          f"  Deq = {pm.equivalent_half_sine_duration * 1e3:.4f} ms  dV = {pm.delta_v_main:6.2f} m/s"
          f"  (Hertz estimate {peak_est:9,.0f} g, {deq_est * 1e3:.4f} ms)  p0 = {p0 / 1e9:.2f} GPa")

for name in stacks:
    hh = np.array([h for n_, h in designs if n_ == name])
    pk = np.array([res[(name, h)]["pm"].peak_g for h in hh])
    dq = np.array([res[(name, h)]["pm"].equivalent_half_sine_duration for h in hh])
    a_pk = np.polyfit(np.log(hh), np.log(pk), 1)[0]
    a_d = np.polyfit(np.log(hh), np.log(dq), 1)[0]
    print(f"{name}: peak ~ h^{a_pk:.3f}, duration ~ h^{a_d:.3f}  (Hertz: 0.6, -0.1)")
    assert abs(a_pk - 0.6) < 0.05 and abs(a_d + 0.1) < 0.03
steel_d = [res[("steel", h)]["pm"].equivalent_half_sine_duration for h in heights]
nylon_d = [res[("nylon cap", h)]["pm"].equivalent_half_sine_duration for h in heights]
assert max(steel_d) < 0.1e-3 < 0.12e-3  # every all-steel pulse is shorter than every standard's duration
assert 0.17e-3 < min(nylon_d) and max(nylon_d) < 0.30e-3

# %% [markdown]
# ### Which conditions can each stack meet?
#
# Peak rises and duration falls with the drop height, so a condition `(A, D)` is met for heights
# between `h_A` (peak = A) and `h_D` (duration = D), if `h_A < h_D`; both are interpolated as power
# laws between the simulated drops (1 cm … 1 m only; nothing is extrapolated).

# %%
def window(name, A, D):
    hh = np.array([h for n_, h in designs if n_ == name])
    pk = np.log([res[(name, h)]["pm"].peak_g for h in hh])
    dq = np.log([res[(name, h)]["pm"].equivalent_half_sine_duration for h in hh])
    lh = np.log(hh)
    h_A = np.exp(np.interp(np.log(A), pk, lh, left=-np.inf, right=np.inf))  # peak rises with h
    h_D = np.exp(np.interp(-np.log(D), -dq, lh, left=-np.inf, right=np.inf))  # duration falls with h
    lo, hi = max(h_A, hh[0]), min(h_D, hh[-1])
    return (lo, hi) if lo < hi else None


rows_w = []
for name in stacks:
    for s, c, A, D, src in LEVELS:
        w = window(name, A, D)
        rows_w.append((name, s, c, A, D, w[0] if w else float("nan"), w[1] if w else float("nan"), src))
        if w:
            print(f"{name:9s} meets {s} {c} ({A} g, {D * 1e3} ms) for drops {w[0]:.3f} - {w[1]:.3f} m")
met = {(r[0], r[1], r[2]) for r in rows_w if np.isfinite(r[5])}
assert not any(n_ == "steel" for n_, _, _ in met)  # all-steel: durations too short for every condition
assert met == {("nylon cap", "MIL-STD-883 M2002", "E")}  # nylon cap: MIL-STD-883 E only
wE = window("nylon cap", 10000, 0.2e-3)
assert 0.12 < wE[0] < 0.2 < wE[1] < 0.4

# the simulated drop of 0.2 m with the nylon cap: meets E, and its SRS covers E's half-sine
r02 = res[("nylon cap", 0.2)]
v02 = judge(r02["pm"].peak_g, r02["pm"].equivalent_half_sine_duration, r02["srs"])
print(f"nylon cap, 0.2 m: {r02['pm'].peak_g:,.0f} g, {r02['pm'].equivalent_half_sine_duration * 1e3:.3f} ms;"
      f" SRS / E half-sine >= {v02[('MIL-STD-883 M2002', 'E')][2]:.3f}")
assert v02[("MIL-STD-883 M2002", "E")][:2] == (True, True)
# the all-steel drop of 0.2 m: no condition met, but its SRS covers E (velocity change 16 m/s > 12.5 m/s)
s02 = res[("steel", 0.2)]
vs02 = judge(s02["pm"].peak_g, s02["pm"].equivalent_half_sine_duration, s02["srs"])
assert vs02[("MIL-STD-883 M2002", "E")][:2] == (False, True)

fig, axs = plt.subplots(1, 2, figsize=(13, 4.8))
ax = axs[0]
for name, mk in (("steel", "o-"), ("nylon cap", "s-")):
    dd = [res[(name, h)]["pm"].equivalent_half_sine_duration * 1e3 for h in heights]
    pp = [res[(name, h)]["pm"].peak_g for h in heights]
    ax.loglog(dd, pp, mk, label=f"MVG6, {name}, drops {heights[0]:g}–{heights[-1]:g} m")
    for h, d_, p_ in zip(heights, dd, pp):
        ax.annotate(f"{h:g} m", (d_, p_), fontsize=6, xytext=(3, -8), textcoords="offset points")
for s, c, A, D, _ in LEVELS:
    mark = "v" if s.startswith("MIL") else "^"
    ax.loglog(D * 1e3, A, mark, color="C3" if s.startswith("MIL") else "C2", ms=7)
    ax.annotate(f"{'883' if s.startswith('MIL') else 'B110'} {c}", (D * 1e3, A), fontsize=7, xytext=(4, 2),
                textcoords="offset points")
ax.loglog(p.equivalent_half_sine_duration * 1e3, p.peak_g, "k*", ms=10, label="examples/steel_materials.toml (10 cm)")
ax.set(xlabel="equivalent half-sine duration (ms)", ylabel="peak (g)",
       title="Predicted top pulses vs test conditions (▼ MIL-STD-883 M2002, ▲ JESD22-B110; no paper figure)")
ax.legend(fontsize=7, loc="lower left")
ax = axs[1]
ax.loglog(FREQ, r02["srs"], "C1", lw=1.5, label="MVG6 nylon cap, 0.2 m")
ax.loglog(FREQ, s02["srs"], "C0", lw=1.5, label="MVG6 all steel, 0.2 m")
ax.loglog(FREQ, HS_SRS[("MIL-STD-883 M2002", "E")], "k--", lw=1, label="MIL-STD-883 E half-sine (10,000 g, 0.2 ms)")
ax.set(xlabel="natural frequency (Hz)", ylabel="maximax SRS, Q = 10 (g)", title="SRS at 0.2 m drop against condition E (no paper figure)")
ax.legend(fontsize=8)
show(fig, "pulse_mvg6_steel_vs_conditions")

# %% [markdown]
# ### Caveat: the contacts are not elastic at these loads
#
# The Hertz peak pressure of the top contact, `p₀ = (6 F E*²/(π³ R*²))^{1/3}` (Johnson 1985, §4.2),
# is printed above: 7–17 GPa for the steel spheres and 0.4–1.0 GPa against nylon. First yield
# under a Hertz contact occurs at `p₀ ≈ 1.6 Y` (Johnson 1985, §6.2); the yield strengths are not in
# `data/materials.csv` (hardened bearing steel is of order 2 GPa, nylon of order 0.1 GPa — check a
# datasheet), so every drop here loads the top contact far into the plastic range. The viscoelastic
# law cannot represent that: the real pulses will be lower and longer, and the restitution lower,
# than predicted. The elastic predictions are upper bounds on the peak; a test rig needs measured
# restitution and pulse data (or flat, larger contact faces that keep `p₀` below yield).

# %%
p0_all = [r[-1] for r in rows_b]
assert min(p0_all) > 0.1  # GPa: above the order-of-magnitude yield onset of nylon, let alone steel loads
write_table("shock_test_levels", ["standard", "condition", "peak_g", "duration_s", "delta_v_mps", "source"],
            [(s, c, A, D, 2 * A * G0 * D / np.pi, src) for s, c, A, D, src in LEVELS],
            ["Half-sine shock-test conditions: peak acceleration (g = 9.80665 m/s^2), duration (s), velocity",
             "change 2AD/pi (m/s). Levels as listed in docs/references.md, \"Test levels\", from secondary sources; not checked",
             "against the standards' texts. Generated by notebooks/07_pulse_prediction.py"])
write_table("pulse_mvg6_steel_vs_height",
            ["variant", "drop_height_m", "v_ff_mps", "gain_G", "peak_g", "duration_10pct_s", "equivalent_half_sine_s",
             "delta_v_mps", "hertz_estimate_peak_g", "hertz_estimate_duration_s", "hertz_peak_pressure_GPa"], rows_b,
            ["Six-mass MVG stack (R = 0.012, m_1 = 8.4 kg, Eq 15) of steel-52100 spheres on a steel-4340 anvil",
             "(data/materials.csv), top mass steel or nylon-66 capped; viscoelastic contacts, e = 0.9 (nylon 0.75)",
             "calibrated at the rigid approach speeds of a 0.1 m drop; gaps 2 mm; gravity 9.80665 m/s^2.",
             "Top-mass accelerometer pulse (analyse). Generated by notebooks/07_pulse_prediction.py"])
write_table("pulse_condition_windows", ["variant", "standard", "condition", "peak_g", "duration_s",
                                        "drop_height_min_m", "drop_height_max_m", "level_source"], rows_w,
            ["Drop heights (m) over which the predicted top pulse is at least as severe as the condition in peak",
             "and equivalent half-sine duration (NaN: never, within 1 cm - 1 m). Generated by notebooks/07_pulse_prediction.py"])
write_table("pulse_example_file", ["quantity", "value"],
            [("v_ff_mps", v_ff), ("gain_G", rep.top_velocity_gain), ("peak_g", p.peak_g),
             ("duration_10pct_s", p.duration_10), ("equivalent_half_sine_s", p.equivalent_half_sine_duration),
             ("delta_v_mps", p.delta_v_main), ("srs_max_g", float(srs_ex.max()))],
            ["examples/steel_materials.toml simulated (10 cm drop); top-mass pulse. SI units, g = 9.80665 m/s^2.",
             "Generated by notebooks/07_pulse_prediction.py"])
print(f"notebook time {time.perf_counter() - T0:.1f} s")

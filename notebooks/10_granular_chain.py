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
# # 10. Long granular chains: the solitary wave, a tapered chain, a dissipative chain
#
# A row of touching beads is the limit of a shock amplifier without gaps. Struck at one end, a chain of
# equal Hertz beads carries a *solitary wave* (Nesterenko 1983, "Propagation of nonlinear compression
# pulses in granular media", J. Appl. Mech. Tech. Phys. 24, 733; *Dynamics of Heterogeneous Materials*,
# 2001): a compression pulse about five beads long that runs unchanged at a speed set by its own
# amplitude. This notebook runs it on a 200-bead chain (60 in the quick mode) and checks:
#
# 1. **Speed and amplitude** against the discrete chain's numbers
#    (docs/references.md, "Stacks and chains": peak bead velocity `0.6816 v0` for an equal striker,
#    speed `0.9075 (k/m)^{2/5} v_m^{1/5}` beads per second) and Nesterenko's continuum solution (`(16/25)^{1/5} = 0.9146`, 0.8 % faster);
# 2. **Width** against the continuum's profile: strain `∝ cos⁴(√10 x / (5a))` over one wavelength of
#    `π√10/2 ≈ 4.97` bead diameters `a`, so the force (`∝ strain^{3/2}`) has a half-maximum width of
#    `(10/√10) arccos(2^{-1/6}) = 1.491` beads;
# 3. **A tapered chain** (masses falling by a fixed ratio per bead, Sen et al.): how the end bead's
#    launch grows with the taper;
# 4. **A dissipative chain** with Hertz plus a linear dashpot (Rosas, Romero, Nesterenko & Lindenberg
#    2007, Phys. Rev. Lett. 99, 164301; `law = "hertz-dashpot"`): the wave's amplitude decays along the
#    chain;
# 5. **A precompressed chain** on a wall, pressed by a static end force `F0` (`hc.precompressed`): the
#    wave's speed from the report against Nesterenko's continuum solution for precompressed chains,
#    from the sound speed `c0` (weak waves) to the strongly nonlinear limit.
#
# Beads: 1 cm steel balls, m = 4.5 g, k = 1.2e10 N/m^1.5, no ground, no gravity, touching without
# precompression; the striker is bead 1.

# %%
import time

import matplotlib.pyplot as plt
import numpy as np
from _nbutil import QUICK, show, write_table

import hertz_chain as hc

T0 = time.perf_counter()
N = 60 if QUICK else 200
M, K, V0 = 0.0045, 1.2e10, 1.0
TOL = hc.Tolerances(rtol=1e-11, atol=1e-11)
T_C = 3.21807 * (0.5 * M / K) ** 0.4 * V0**-0.2  # Hertz contact time of two beads at V0


def chain(masses, law=None, v0=V0):
    n = len(masses)
    stack = hc.Stack(np.asarray(masses, float), law or hc.Hertz(K), gravity=0.0, ground=False)
    v = np.zeros(n)
    v[0] = v0
    return stack, hc.State(np.zeros(n), v)


def run(masses, law=None, points_per_tc=16, span=1.4):
    stack, state = chain(masses, law)
    n = len(masses)
    grid = np.linspace(0.0, span * n * T_C, int(points_per_tc * span * n))
    sol = hc.simulate(stack, state, ts=grid, tolerances=TOL, max_steps=200 * n + 4096)
    return sol


def refine_peak(t, y, i):
    """Time and value of the parabola through the samples i-1, i, i+1."""
    y0, y1, y2 = y[i - 1], y[i], y[i + 1]
    den = y0 - 2 * y1 + y2
    h = t[1] - t[0]
    return t[i] + 0.5 * h * (y0 - y2) / den, y1 - 0.125 * (y2 - y0) ** 2 / den


sol = run(np.full(N, M))
g = sol.grid
F = np.asarray(g.forces)
V = np.asarray(g.velocities)
print(f"{N} beads: {sol.num_steps} steps, status {sol.status.name}, energy error {sol.energy_error:.1e}")

# %% [markdown]
# ## 1. Speed and amplitude
#
# Peak times of every contact force, refined by a parabola through the grid samples; the speed is the
# slope of bead number against peak time over the middle of the chain, where the wave has formed.

# %%
t_peak, v_peak = [], []
for j in range(1, N):
    i = int(np.nanargmax(F[:, j]))
    t_peak.append(refine_peak(g.t, F[:, j], i)[0])
for b in range(N - 1):
    i = int(np.nanargmax(V[:, b]))
    v_peak.append(refine_peak(g.t, V[:, b], i)[1])
t_peak, v_peak = np.asarray(t_peak), np.asarray(v_peak)
mid = slice(N // 4, 3 * N // 4)
speed = np.polyfit(t_peak[mid], np.arange(1, N)[mid], 1)[0]  # interfaces per second = beads per second
v_m = float(np.median(v_peak[mid]))
c_disc = speed / ((K / M) ** 0.4 * v_m**0.2)
print(f"peak bead velocity {v_m / V0:.5f} v0 (reference 0.6816); speed {speed:.1f} beads/s = {c_disc:.5f} "
      f"(k/m)^(2/5) v_m^(1/5) (discrete reference 0.9075, continuum {(16 / 25) ** 0.2:.4f})")
assert abs(v_m / V0 - 0.6816) < 1e-4
assert abs(c_disc - 0.9075) < 1e-4
assert c_disc < (16 / 25) ** 0.2  # the discrete wave is slower than the continuum's
write_table("granular_solitary_wave", ["quantity", "value", "reference"],
            [("peak bead velocity / v0", v_m / V0, 0.6816), ("speed / ((k/m)^0.4 v_m^0.2)", c_disc, 0.9075)],
            [f"notebooks/10_granular_chain.py: {N} equal Hertz beads, m = {M} kg, k = {K:g} N/m^1.5, striker {V0} m/s"])

# %% [markdown]
# ## 2. Width against the continuum solution
#
# The force pulse's half-maximum width (each middle contact's pulse in time, times the wave's speed)
# against the continuum's, and a snapshot of the force along the chain when the wave is in the middle,
# against the continuum profile `F ∝ cos⁶(√10 x / (5a))` centred on the same peak.

# %%
i_mid = int(np.nanargmax(F[:, N // 2]))
profile = F[i_mid, 1:]
j0 = int(np.argmax(profile))
x = np.arange(1, N) - (j0 + 1)


def half_width(xs, ys):
    """Width at half the maximum of the peak of `ys` over `xs`, by linear interpolation on both flanks."""
    k, half = int(np.argmax(ys)), 0.5 * ys.max()
    lo = next(i for i in range(k, 0, -1) if ys[i - 1] < half)
    hi = next(i for i in range(k, len(ys) - 1) if ys[i + 1] < half)
    x_lo = xs[lo - 1] + (half - ys[lo - 1]) / (ys[lo] - ys[lo - 1]) * (xs[lo] - xs[lo - 1])
    x_hi = xs[hi] + (ys[hi] - half) / (ys[hi] - ys[hi + 1]) * (xs[hi + 1] - xs[hi])
    return x_hi - x_lo


# the width in beads: each middle contact's force pulse in time (16 samples per contact time, finely
# resolved) at half its maximum, times the wave's speed. (A snapshot along the chain samples the profile at
# whole beads only, and linear interpolation between them widens a peaked profile: it read 1.61 beads.)
fwhm = float(np.mean([half_width(np.asarray(g.t), np.nan_to_num(F[:, j])) for j in range(N // 4, 3 * N // 4)])) * speed
theta = np.sqrt(10) * x / 5
cont = np.where(np.abs(theta) <= np.pi / 2, np.cos(theta) ** 6, 0.0) * profile.max()
fwhm_cont = 2 * 5 / np.sqrt(10) * np.arccos(2 ** (-1 / 6))
beads_loaded = int(np.sum(profile > 1e-3 * profile.max()))
print(f"half-maximum width {fwhm:.3f} beads (continuum {fwhm_cont:.3f}); "
      f"contacts above 0.1 % of the peak: {beads_loaded} (continuum wavelength {np.pi * np.sqrt(10) / 2:.2f} beads)")
assert 4 <= beads_loaded <= 7  # "about five beads" (Nesterenko)
assert abs(fwhm / fwhm_cont - 1) < 0.15  # the discrete wave is close to the continuum's shape

fig, axs = plt.subplots(1, 2, figsize=(12, 4), constrained_layout=True)
for j in (5, N // 4, N // 2, 3 * N // 4):
    axs[0].plot(g.t * 1e3, F[:, j] / 1e3, label=f"contact {j}")
axs[0].set(xlabel="t (ms)", ylabel="contact force (kN)", title="The solitary wave passing contacts along the chain")
axs[0].legend(fontsize=8)
axs[0].grid(alpha=0.3)
axs[1].plot(x, profile / 1e3, "o", label=f"hertz_chain, t = {g.t[i_mid] * 1e3:.3f} ms")
xf = np.linspace(-3, 3, 200)
tf = np.sqrt(10) * xf / 5
axs[1].plot(xf, np.where(np.abs(tf) <= np.pi / 2, np.cos(tf) ** 6, 0) * profile.max() / 1e3, "-",
            label="continuum cos⁶(√10 x / 5a) (Nesterenko)")
axs[1].set(xlim=(-6, 6), xlabel="contact number relative to the peak", ylabel="contact force (kN)",
           title="Wave profile along the chain")
axs[1].legend(fontsize=8)
axs[1].grid(alpha=0.3)
show(fig, "10_solitary_wave")

# %% [markdown]
# ## 3. A tapered chain
#
# Masses falling by a factor `1 − q` per bead (Sen and co-workers' tapered chains): the end bead leaves
# faster as the taper steepens. Reference for the trend: with gaps (independent elastic collisions) the
# chain would follow Eq 13, `Π 2/(1 + r)`; touching, the collisions overlap and the gain is lower.

# %%
n_t = 20 if QUICK else 40
tapers = [0.0, 0.1] if QUICK else [0.0, 0.02, 0.05, 0.1, 0.15]
rows = []
for q in tapers:
    masses = M * (1 - q) ** np.arange(n_t)
    s = run(masses, points_per_tc=4)
    g_end = float(np.asarray(s.launch_velocities)[-1]) / V0
    rigid = float(hc.chain_gain(masses, 1.0))  # Eq 13, e = 1
    rows.append((q, g_end, rigid))
    print(f"taper q = {q:.2f}: end bead leaves at {g_end:.4f} v0 (independent collisions, Eq 13: {rigid:.4f})")
gains = np.array([r[1] for r in rows])
assert np.all(np.diff(gains) > 0)  # a steeper taper launches the end bead faster
assert np.all(gains <= np.array([r[2] for r in rows]) + 1e-9)  # never above the independent-collision gain
write_table("granular_tapered_chain", ["taper", "end_gain", "eq13_gain"], rows,
            [f"notebooks/10_granular_chain.py: {n_t} touching Hertz beads, masses M (1 - q)^i, striker = bead 1"])

# %% [markdown]
# ## 4. A dissipative chain
#
# Hertz with a linear dashpot between the beads, calibrated to a restitution `e` at the striker speed:
# the wave loses amplitude as it runs (Rosas et al. 2007). The peak force of every contact, relative to
# the elastic chain's.

# %%
fig, ax = plt.subplots(figsize=(7, 4), constrained_layout=True)
n_d = min(N, 60)
for e in ([0.9] if QUICK else [0.98, 0.95, 0.9, 0.8]):
    law = hc.make_law("hertz-dashpot", stiffness=K, restitution=e, effective_mass=M / 2, calibration_velocity=V0)
    s = run(np.full(n_d, M), law)
    peaks = np.nanmax(np.asarray(s.grid.forces)[:, 1:], axis=0)
    ax.semilogy(np.arange(1, n_d), peaks / 1e3, label=f"e = {e} at {V0} m/s")
    assert np.all(np.diff(peaks[n_d // 4 :]) < 0)  # the amplitude decays along the chain
ax.semilogy(np.arange(1, N), np.nanmax(F[:, 1:], axis=0) / 1e3, "k--", label="elastic")
ax.set(xlim=(0, n_d), xlabel="contact number", ylabel="peak contact force (kN)",
       title="Dissipative chain: the wave decays (Hertz + linear dashpot)")
ax.legend(fontsize=8)
ax.grid(alpha=0.3, which="both")
show(fig, "10_dissipative_chain")

# %% [markdown]
# ## 5. A precompressed chain
#
# 40 beads on a wall (the ground, no gravity), pressed by `F0` on the far bead, which is struck toward
# the wall at 0.2 m/s. Every contact starts at `delta_0 = (F0/k)^{2/3}`; small waves travel at the sound
# speed `c0 = sqrt(k_1/m)` contacts per second, `k_1 = 1.5 k^{2/3} F0^{1/3}`. Nesterenko's continuum
# solitary wave (Nesterenko 2001, *Dynamics of Heterogeneous Materials*, Ch. 1) runs at
# `V_s = c0 / (xi - 1) · sqrt(4/15 · (3 + 2 xi^{5/2} - 5 xi))`, `xi = delta_m/delta_0 = (F_m/F0)^{2/3}`
# with `F_m` the wave's peak force: `c0` as `xi -> 1`, and the uncompressed wave's `(16/25)^{1/5}` law as
# `xi -> inf`. The run stops at `0.8 N / c0`, before the wave's reflection from the wall comes back to the
# middle of the chain; the speed is the report's `wave_speed` (peak-force times of the middle half).
# Near `xi = 1` (strong precompression, a weak strike) 40 beads are too few for a solitary wave to form:
# the strike makes a dispersive train whose peaks run a little slower than `c0` (the discrete chain's
# group velocity is below `c0`), so the agreement there is a few per cent, not better.

# %%
n_p = 40
rows = []
for f0 in ([5.0, 500.0] if QUICK else [0.5, 5.0, 50.0, 500.0]):
    stack, rest = hc.precompressed(hc.Stack(np.full(n_p, M), hc.Hertz(K), gravity=0.0), f0)
    v = np.zeros(n_p)
    v[-1] = -0.2
    c0 = np.sqrt(1.5 * K ** (2 / 3) * f0 ** (1 / 3) / M)
    s = hc.simulate(stack, hc.State(rest.positions, v), until="t_max", t_max=0.8 * n_p / c0, tolerances=TOL,
                    max_steps=200_000)
    rep = hc.analyse(s)
    peaks = np.array([max((ep.peak_force for ep in rep.episodes if ep.interface == j), default=np.nan)
                      for j in range(n_p)])
    xi = (np.median(peaks[n_p // 4 : 3 * n_p // 4]) / f0) ** (2 / 3)
    v_s = c0 / (xi - 1) * np.sqrt(4 / 15 * (3 + 2 * xi**2.5 - 5 * xi))
    rows.append((f0, xi, -rep.wave_speed, c0, v_s, -rep.wave_speed / v_s))
    print(f"F0 = {f0:6.1f} N: xi = {xi:6.3f}, wave {-rep.wave_speed:9.0f} contacts/s, c0 {c0:9.0f}, "
          f"continuum V_s {v_s:9.0f} (ratio {-rep.wave_speed / v_s:.4f})")
    assert rep.wave_speed < 0  # travelling down, toward the wall
    assert abs(-rep.wave_speed / v_s - 1) < 0.05  # the discrete chain against the continuum solution
write_table("granular_precompressed", ["F0_N", "xi", "wave_speed_per_s", "c0_per_s", "continuum_Vs_per_s", "ratio"],
            rows, [f"notebooks/10_granular_chain.py: {n_p} Hertz beads on a wall pressed by F0, far bead struck at 0.2 m/s"])
print(f"notebook time {time.perf_counter() - T0:.1f} s")

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
# # 1. Impact between two masses (seed paper Section 2, Figs 2–4)
#
# Two point masses `m1 > m2` collide with velocities `v1`, `v2` (upward-positive); `r = m2/m1` (Eq 5),
# `g = v2/v1` (Eq 6), restitution `e` (Eq 2). The paper draws three families of surfaces over `(r, g)`
# or `(r, e)`:
#
# * Fig 2 — velocity gains `A1 = V1/v1`, `A2 = V2/v2` (Eqs 3–4) for `e = 0.8`;
# * Fig 3 — the initial velocity ratio for which `m1` (Eq 7) or `m2` (Eq 8, corrected) is at rest after impact;
# * Fig 4 — kinetic-energy transfer efficiencies `K1`, `K2` (Eqs 10–11) for `e = 0.8`.
#
# The surfaces come from `hertz_chain.rigid`; each key statement is re-derived here from momentum
# conservation (Eq 1) and the definition of restitution (Eq 2) with plain numpy, and asserted.
#
# **Caption misprints noticed while reproducing:** Fig 2's caption says "for `r_{2,1} = 0.8`", but the
# surfaces are drawn over `r` and the text says `e_{2,1} = 0.8` (we use `e = 0.8`). Fig 4's caption says
# "`e_{2,1} < 0.8`", the text "again for … 0.8" (we use `e = 0.8`).

# %%
import numpy as np
import matplotlib.pyplot as plt

from _nbutil import QUICK, show, write_table
from hertz_chain import rigid

E = 0.8  # the paper's "representative high coefficient of restitution" (Section 2)
N = 41 if QUICK else 121


def post_impact(m1, m2, v1, v2, e):
    """Independent solution of Eqs 1–2: momentum and restitution, two linear equations in V1, V2."""
    A = np.array([[m1, m2], [-1.0, 1.0]])
    b = np.array([m1 * v1 + m2 * v2, -e * (v2 - v1)])
    return np.linalg.solve(A, b)


# %% [markdown]
# ## Fig 2 — velocity gains `A1`, `A2` against `r` and `g` (Eqs 3–4), `e = 0.8`
#
# Collisions need `g < 1`; the paper's axis runs to `−∞`. We draw `g ∈ [−5, 0.9]` and stop short of
# `g = 0`, where `A2` is infinite (target at rest): the `g` grid skips a band around 0.

# %%
r = np.linspace(0.02, 1.0, N)
g = np.concatenate([np.linspace(-5.0, -0.05, N // 2), np.linspace(0.05, 0.9, N // 2)])
RR, GG = np.meshgrid(r, g)
A1, A2 = rigid.velocity_gains(RR, GG, E)

# independent check of Eqs 3-4 at random points against the 2x2 solve of Eqs 1-2
rng = np.random.default_rng(0)
for _ in range(20):
    ri, gi, ei = rng.uniform(0.05, 1), rng.uniform(-5, 0.95), rng.uniform(0.1, 1)
    if abs(gi) < 1e-3:
        continue
    V1, V2 = post_impact(1.0, ri, 1.0, gi, ei)
    a1, a2 = rigid.velocity_gains(ri, gi, ei)
    assert np.isclose(a1, V1 / 1.0, rtol=1e-12) and np.isclose(a2, V2 / gi, rtol=1e-12)  # Eqs 3-4 from Eqs 1-2

fig = plt.figure(figsize=(11, 4.5))
for k, (Z, name) in enumerate(((A1, "A1 = V1/v1"), (np.clip(A2, -10, 10), "A2 = V2/v2 (clipped to ±10)"))):
    ax = fig.add_subplot(1, 2, k + 1, projection="3d")
    ax.plot_surface(RR, GG, Z, cmap="viridis", linewidth=0)
    ax.set(xlabel="mass ratio r = m2/m1", ylabel="velocity ratio g = v2/v1", zlabel=name)
fig.suptitle("Reproduces seed-paper Fig 2 (Eqs 3–4, e = 0.8; caption's 'r = 0.8' read as e = 0.8)")
show(fig, "fig02_velocity_gains")

# %% [markdown]
# Section 3 of the paper: "in a perfectly elastic collision between two masses that approach each other
# with equal and opposite velocities, with one of the masses being at least three times as heavy as the
# other one, the lighter mass rebounds with a velocity that is more than twice its velocity before
# impact." With `g = −1`, `e = 1`: `A2 = 1 − 2·2/(1 + r) = −2` exactly at `r = 1/3`, and `|A2| > 2` for `r < 1/3`.

# %%
_, a2_third = rigid.velocity_gains(1 / 3, -1.0, 1.0)
assert np.isclose(a2_third, -2.0, rtol=1e-14)  # Eq 4 with r = 1/3, g = -1, e = 1
_, a2_lighter = rigid.velocity_gains(np.array([0.1, 0.2, 0.3]), -1.0, 1.0)
assert np.all(np.abs(a2_lighter) > 2)  # Section 3 statement reproduces
print("A2(r=1/3, g=-1, e=1) =", a2_third)

# %% [markdown]
# ## Fig 3 — the `V1 = 0` (Eq 7) and `V2 = 0` (Eq 8, corrected) surfaces over `(r, e)`
#
# Eq 7: `g = (e − 1/r)/(1 + e)` makes `A1 = 0`. Eq 8 is printed with `r_{2,3}`, a mass that does not
# exist in the two-body problem; from Eq 4 with `A2 = 0` the condition is `g = (1 + e)/(e − r_{2,1})`
# (docs/references.md, "Seed paper misprints"). We check both by substitution into Eqs 3–4 and into Eqs 1–2.
#
# A finding the figure hides: the corrected `V2 = 0` surface lies in the collision range `g < 1` only
# where `r > e` (then `g < 0`, a head-on impact). For `r < e` the formula gives `g > 1`: the masses
# never meet, so the "lower surface" of Fig 3 exists only over the part `r > e` of the `(r, e)` square.

# %%
r3 = np.linspace(0.05, 1.0, N)
e3 = np.linspace(0.05, 1.0, N)
R3, E3 = np.meshgrid(r3, e3)
g_v1 = rigid.velocity_ratio_m1_at_rest(R3, E3)
with np.errstate(divide="ignore"):
    g_v2 = rigid.velocity_ratio_m2_at_rest(R3, E3)

a1_on, _ = rigid.velocity_gains(R3, g_v1, E3)
assert np.max(np.abs(a1_on)) < 1e-12  # Eq 7 gives V1 = 0 (Eq 3)
ok = R3 > E3 + 1e-9
_, a2_on = rigid.velocity_gains(R3[ok], g_v2[ok], E3[ok])
assert np.max(np.abs(a2_on)) < 1e-12  # corrected Eq 8 gives V2 = 0 (Eq 4)
V1, V2 = post_impact(1.0, 0.9, 1.0, float(rigid.velocity_ratio_m2_at_rest(0.9, 0.6)), 0.6)
assert abs(V2) < 1e-12  # ... and by the independent 2x2 solve of Eqs 1-2
# the printed Eq 8 cannot be evaluated (r_{2,3} undefined); the region where the corrected surface is a collision:
assert np.all(g_v2[ok] < 0) and np.all(g_v2[(R3 < E3 - 1e-9)] > 1)

fig = plt.figure(figsize=(6.5, 5))
ax = fig.add_subplot(projection="3d")
ax.plot_surface(R3, E3, g_v1, cmap="Blues", linewidth=0, alpha=0.9)
Z = np.where(ok, np.clip(g_v2, -40, 1), np.nan)
ax.plot_surface(R3, E3, Z, cmap="Oranges", linewidth=0, alpha=0.9)
ax.set(xlabel="r = m2/m1", ylabel="e", zlabel="g = v2/v1")
ax.set_title("Reproduces Fig 3: V1 = 0 (Eq 7, blue) and V2 = 0 (Eq 8 with r_{2,1}, orange).\n"
             "Orange drawn only where r > e (elsewhere g > 1: no collision); clipped at g = −40", fontsize=9)
show(fig, "fig03_at_rest_surfaces")

# %% [markdown]
# Eq 9: with `V1 = v2 = 0`, Eq 7 with `g = 0` forces `r = 1/e` (so `m2 = m1/e ≥ m1`, outside the
# paper's `m1 > m2`), and then `G2 = V2/v1 = 1/r = e`: no amplification. Checked with Eqs 1–2:

# %%
for e9 in (0.5, 0.8, 1.0):
    V1, V2 = post_impact(1.0, 1 / e9, 1.0, 0.0, e9)
    assert abs(V1) < 1e-12 and np.isclose(V2, e9, rtol=1e-12)  # Eq 9: G2 = 1/r = e

# %% [markdown]
# ## Fig 4 — energy transfer efficiencies `K1`, `K2` (Eqs 10–11), `e = 0.8`

# %%
K1, K2 = rigid.energy_efficiencies(RR, GG, E)
# independent: kinetic energies from the 2x2 solve
for _ in range(20):
    ri, gi = rng.uniform(0.05, 1), rng.uniform(-5, 0.95)
    V1, V2 = post_impact(1.0, ri, 1.0, gi, E)
    k1, k2 = rigid.energy_efficiencies(ri, gi, E)
    ke0 = 1.0 + ri * gi**2
    assert np.isclose(k1, V1**2 / ke0, rtol=1e-12) and np.isclose(k2, ri * V2**2 / ke0, rtol=1e-12)  # Eqs 10-11
assert np.all(K1 + K2 < 1)  # Section 2.1: e < 1 loses energy ("K1 + K2 < 1")
k1e, k2e = rigid.energy_efficiencies(RR, GG, 1.0)
assert np.allclose(k1e + k2e, 1.0, rtol=1e-12)  # e = 1: K1 + K2 = 1
# Eq 12 (g = 0): K2 = r (1+e)^2/(1+r)^2, largest at r = 1: (1+e)^2/4 = 0.81 for e = 0.8 (Hart & Herrmann)
_, k2_0 = rigid.energy_efficiencies(r, 0.0, E)
assert np.allclose(k2_0, r * (1 + E) ** 2 / (1 + r) ** 2, rtol=1e-13)
assert np.isclose(k2_0.max(), 0.81, rtol=1e-12)

fig = plt.figure(figsize=(11, 4.5))
for k, (Z, name) in enumerate(((K1, "K1"), (K2, "K2"))):
    ax = fig.add_subplot(1, 2, k + 1, projection="3d")
    ax.plot_surface(RR, GG, Z, cmap="magma", linewidth=0)
    ax.set(xlabel="r = m2/m1", ylabel="g = v2/v1", zlabel=name)
fig.suptitle("Reproduces Fig 4 (Eqs 10–11, e = 0.8; caption's 'e < 0.8' read as e = 0.8)")
show(fig, "fig04_energy_efficiencies")

# %% [markdown]
# The Fig 3 surfaces at a few points, as a table (written with `HERTZ_CHAIN_WRITE_TABLES=1`).

# %%
pts = [(rr, ee) for ee in (0.5, 0.8, 1.0) for rr in (0.1, 0.3, 0.5, 0.9)]
rows = []
for rr, ee in pts:
    gv1 = float(rigid.velocity_ratio_m1_at_rest(rr, ee))
    gv2 = float(rigid.velocity_ratio_m2_at_rest(rr, ee)) if rr != ee else float("nan")
    rows.append((rr, ee, gv1, gv2, bool(rr > ee)))
write_table("two_mass_at_rest", ["r", "e", "g_V1_zero_eq7", "g_V2_zero_eq8_corrected", "V2_zero_is_a_collision"],
            rows, ["Seed paper Eqs 7 and 8 (corrected: r_{2,1} for the printed r_{2,3}); dimensionless.",
                   "Generated by notebooks/01_two_mass_impact.py"])
for row in rows:
    print(row)

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
# # 2. Maximum-velocity-gain (MVG) chains and stacks (Sections 3–4.1, Figs 7–9)
#
# Power-law masses `r_{i,i−1} = R^{1/(n−1)}` (Eq 15), `R = m_n/m_1` (Eq 14).
#
# * Horizontal chain, `m_1` strikes the others at rest: `G_n = [(1+e)/(1+R^{1/(n−1)})]^{n−1}` (Eq 16),
#   elastic limit `1/√R` (Eq 18).
# * Dropped vertical stack: `G_n = (1+e)^n/(1+R^{1/(n−1)})^{n−1} − 1` (Eq 20), elastic limit
#   `(2 − √R)/√R` (Eq 21); optimal `n_max` by tabulating Eq 20 or by the Pöschel–Brilliantov route
#   (Eqs 22–24, with the misprints of Eqs 23–24 corrected, docs/references.md, "Seed paper misprints").
#
# Figs 7 (G against n and e for R = 0.012), 8 (the `n_max` map) and 9 (the `G*` map). Each number the
# notebook asserts is recomputed here from the printed equation with numpy, independently of
# `hertz_chain.rigid`.

# %%
import numpy as np
import matplotlib.pyplot as plt
from matplotlib.colors import LogNorm
from scipy.optimize import brentq

from _nbutil import QUICK, rel, show, write_table
from hertz_chain import rigid

R0 = 0.012  # Figs 7, 16-17


def g_eq20(R, e, n):
    """Eq 20, typed in from the paper."""
    return (1 + e) ** n / (1 + R ** (1 / (n - 1))) ** (n - 1) - 1


def g_eq16(R, e, n):
    return ((1 + e) / (1 + R ** (1 / (n - 1)))) ** (n - 1)


# %% [markdown]
# ## Eq 15 maximises the gain (Hart & Herrmann; Kerwin; Pöschel & Brilliantov)
# For fixed `n` and `R`, Eq 19 is largest for equal ratios. Random ratio sets with the same product
# never beat the power law (independent event-by-event cascade with Eqs 1–2, `rigid.cascade_velocities`).

# %%
rng = np.random.default_rng(1)
n = 6
best = rigid.mvg_gain(R0, 0.8, n)
for _ in range(200):
    w = rng.dirichlet(np.ones(n - 1))
    ratios = R0 ** w  # product = R0
    masses = np.concatenate([[1.0], np.cumprod(ratios)])
    hit, _ = rigid.cascade_velocities(masses, 0.8, ground_restitution=0.8)
    assert hit[-1] <= best + 1e-12  # Eq 19 with Eq 15 ratios is the maximum (Section 3.1)
assert np.isclose(best, g_eq20(R0, 0.8, 6), rtol=1e-14)

# %% [markdown]
# ## Fig 7 — G against n for several e, R = 0.012 (vertical stack, Eq 20)

# %%
ns = np.arange(2, 21)
es = (0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95, 1.0)
fig, ax = plt.subplots(figsize=(7, 4.5))
for e in es:
    G = rigid.mvg_gain(R0, e, ns)
    assert np.allclose(G, g_eq20(R0, e, ns), rtol=1e-13)
    ax.plot(ns, G, "o-", ms=3, label=f"e = {e}")
    if e < 1:
        nm = int(rigid.mvg_optimal_n(R0, e))
        ax.plot(nm, rigid.mvg_gain(R0, e, nm), "k*", ms=9)
ax.axhline(rigid.mvg_gain_limit(R0), color="grey", ls=":", label="e = 1, n → ∞ (Eq 21)")
ax.set(xlabel="number of masses n", ylabel="G_n = V_n / v_ff", title="Reproduces Fig 7 (Eq 20, R = 0.012); ★ = n_max")
ax.legend(fontsize=7, ncol=2)
show(fig, "fig07_mvg_gain_vs_n")

# %% [markdown]
# Key numbers for `R = 0.012`, `e = 0.8`: `n_max = 6`, `G = 5.0407` (Eq 20, docs/references.md, "Seed paper key numbers").

# %%
n_max = int(rigid.mvg_optimal_n(R0, 0.8))
brute = int(ns[np.argmax(g_eq20(R0, 0.8, ns))])
assert n_max == 6 and brute == 6  # Eq 20 tabulated (Fig 7)
assert np.isclose(rigid.mvg_gain(R0, 0.8, 6), 5.0407, atol=5e-5)  # docs/references.md, "Seed paper key numbers"
print("n_max =", n_max, " G =", rigid.mvg_gain(R0, 0.8, 6))

# %% [markdown]
# Section 4.1: "for values of `e < 0.35` there is no velocity amplification at all" (Fig 7, R = 0.012).
# The threshold where `max_n G_n = 1` is computed below: **0.3503** — the statement reproduces. (It holds
# for this `R` only: `G*` grows without bound as `R → 0` for any `e > 0`, since `x_0 < e`.)

# %%
def best_gain(e, R=R0):
    return max(g_eq20(R, e, k) for k in range(2, 200))


e_thr = brentq(lambda e: best_gain(e) - 1.0, 0.2, 0.9, xtol=1e-12)
assert abs(e_thr - 0.35) < 0.001  # Section 4.1: "e < 0.35 ... no amplification"
print(f"amplification threshold for R = 0.012: e = {e_thr:.4f}")

# %% [markdown]
# ## Elastic limits (Eqs 18, 21) and the horizontal chain (Eq 16)

# %%
# (1 + R^{1/m})^m = 2^m sqrt(R) (1 + ln²R/(8m) + ...): the limits are approached with relative error ~ ln²R/(8m).
# Eq 20 evaluated as printed overflows (2^n) beyond n ~ 1000, so m = 1000 is used.
for R in (0.1, 0.012, 1e-3):
    big = 1000
    tol = np.log(R) ** 2 / (4 * big)
    assert np.isclose(rigid.mvg_chain_gain(R, 1.0, big), 1 / np.sqrt(R), rtol=tol)  # Eq 18
    assert np.isclose(rigid.mvg_gain(R, 1.0, big), (2 - np.sqrt(R)) / np.sqrt(R), rtol=tol)  # Eq 21
    assert np.allclose(rigid.mvg_chain_gain(R, 0.8, ns), g_eq16(R, 0.8, ns), rtol=1e-13)  # Eq 16
# the stack is the chain struck at (1 + e) v_ff, seen from the falling frame (Section 4): Eq 20 = (1+e) Eq 16 - 1
assert np.allclose(rigid.mvg_gain(R0, 0.8, ns), 1.8 * g_eq16(R0, 0.8, ns) - 1, rtol=1e-13)

fig, ax = plt.subplots(figsize=(7, 4))
for e in (0.6, 0.8, 0.9, 1.0):
    ax.plot(ns, rigid.mvg_chain_gain(R0, e, ns), "o-", ms=3, label=f"chain, e = {e}")
ax.axhline(1 / np.sqrt(R0), color="grey", ls=":", label="1/√R (Eq 18)")
ax.set(xlabel="n", ylabel="G_n = V_n / v_1", title="Horizontal MVG chain (Eq 16), R = 0.012 (no figure in the paper)")
ax.legend(fontsize=8)
show(fig, "mvg_horizontal_chain")

# %% [markdown]
# ## Fig 8 — `n_max` over `(R, e)`; Fig 9 — `G*` over `(R, e)`
#
# Two routes to `n_max` must agree: the search over integer `n` (`mvg_optimal_n`) and Eqs 22–24
# (`mvg_optimal_n_pb`), with Eq 23 read as `1 + x0 = (1+e) x0^{x0/(1+x0)}` and Eq 24 as
# `G* = (1+e)^{n*}/(1+x0)^{n*−1} − 1`. An independent brute-force argmax of Eq 20 is the referee.

# %%
nR, nE = (25, 20) if QUICK else (80, 60)
Rg = np.geomspace(1e-4, 0.5, nR)
eg = np.linspace(0.3, 0.98, nE)
RR, EE = np.meshgrid(Rg, eg)
N_MAX = rigid.mvg_optimal_n(RR, EE)
assert np.array_equal(N_MAX, rigid.mvg_optimal_n_pb(RR, EE))  # Eqs 22-24 (corrected) = tabulated Eq 20
kk = np.arange(2, int(N_MAX.max()) + 3)[:, None, None]
brute = kk[np.argmax(g_eq20(RR[None], EE[None], kk), axis=0), 0, 0]
assert np.array_equal(N_MAX, brute)  # brute-force argmax of Eq 20
GSTAR = rigid.continuous_optimal_gain(RR, EE)
GMAX = rigid.mvg_gain(RR, EE, N_MAX)
assert np.all(GSTAR >= GMAX - 1e-12)  # G* is the maximum over real n
NSTAR = rigid.continuous_optimal_n(RR, EE)
diff = (GSTAR - GMAX) / (1 + GMAX)
gap2, gap_lt2 = diff[NSTAR >= 2].max(), diff[NSTAR < 2].max(initial=0.0)
print(f"largest (G* - G_max)/(1 + G_max): {gap2:.3f} where n* >= 2, {gap_lt2:.3f} where n* < 2")
# "G* (which is very close to G_n^max)", Section 4.1: reproduces within 4 % in 1 + G wherever n* >= 2;
# where n* < 2 (large R, low e) G* belongs to an unbuildable chain of fewer than 2 masses and is up to ~20 % high.
assert gap2 < 0.04

# the corrected Eq 23 root for e = 0.8, checked from the stationarity of ln(1 + G) in n
x0 = rigid.optimal_pair_ratio(0.8)
assert np.isclose(1 + x0, 1.8 * x0 ** (x0 / (1 + x0)), rtol=1e-13)  # Eq 23 (corrected)
ns_star = np.log(R0) / np.log(x0) + 1  # Eq 22
dn = 1e-5
slope = (np.log1p(g_eq20(R0, 0.8, ns_star + dn)) - np.log1p(g_eq20(R0, 0.8, ns_star - dn))) / (2 * dn)
assert abs(slope) < 1e-8  # n* is the stationary point of Eq 20
g_printed = 1.8**ns_star / (1 + R0) ** (ns_star - 1) - 1  # Eq 24 as printed, (1 + R)
g_star = rigid.continuous_optimal_gain(R0, 0.8)
print(f"x0 = {x0:.6f}, n* = {ns_star:.4f}, G* = {g_star:.4f}; Eq 24 as printed gives {g_printed:.2f}")
assert np.isclose(g_star, 5.0638, atol=5e-5) and g_star > rigid.mvg_gain(R0, 0.8, 6)  # Eq 24 corrected: just above G_6
assert g_printed > 4 * g_star  # the printed Eq 24, (1 + R)^{n*-1}, gives 23.77: a misprint, not a rounding

fig, axs = plt.subplots(1, 2, figsize=(12, 4.5))
pc = axs[0].pcolormesh(RR, EE, N_MAX, shading="nearest", norm=LogNorm(), cmap="viridis")
fig.colorbar(pc, ax=axs[0], label="n_max")
axs[0].set(xscale="log", xlabel="R = m_n/m_1", ylabel="e", title="Reproduces Fig 8: n_max (Eq 20 / Eqs 22–24)")
pc = axs[1].pcolormesh(RR, EE, GSTAR, shading="nearest", norm=LogNorm(), cmap="magma")
fig.colorbar(pc, ax=axs[1], label="G*")
axs[1].contour(RR, EE, GSTAR, levels=[1.0], colors="w")
axs[1].set(xscale="log", xlabel="R", ylabel="e", title="Reproduces Fig 9: G* (Eq 24 corrected); white: G* = 1")
show(fig, "fig08_09_nmax_gstar")

# monotonicity stated for Fig 9: G* increases with e and with decreasing R
assert np.all(np.diff(GSTAR, axis=0) > 0) and np.all(np.diff(GSTAR, axis=1) < 0)

# %%
rows = [(float(e), int(k), float(rigid.mvg_gain(R0, e, k))) for e in (0.5, 0.6, 0.7, 0.8, 0.9, 0.95) for k in range(2, 21)]
write_table("mvg_gain_R0.012", ["e", "n", "G_eq20"], rows,
            ["Seed paper Eq 20 (Fig 7): dropped MVG stack gain G_n = V_n/v_ff for R = m_n/m_1 = 0.012.",
             "Dimensionless. Generated by notebooks/02_mvg_chains.py"])
rows = [(float(e), float(R), int(rigid.mvg_optimal_n(R, e)), float(rigid.mvg_gain(R, e, rigid.mvg_optimal_n(R, e))),
         float(rigid.continuous_optimal_n(R, e)), float(rigid.continuous_optimal_gain(R, e)))
        for e in (0.5, 0.7, 0.8, 0.9, 0.95) for R in (1e-3, 0.01, 0.012, 0.05, 0.1, 0.3)]
write_table("mvg_optimum", ["e", "R", "n_max", "G_max_eq20", "n_star_eq22", "G_star_eq24_corrected"], rows,
            ["Seed paper Eqs 20, 22-24 (Figs 8-9); Eq 23 read as 1+x0 = (1+e) x0^(x0/(1+x0)),",
             "Eq 24 as G* = (1+e)^n*/(1+x0)^(n*-1) - 1 (docs/references.md, \"Seed paper misprints\"). Dimensionless.",
             "Generated by notebooks/02_mvg_chains.py"])

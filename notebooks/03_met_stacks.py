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
# # 3. Maximum-energy-transfer (MET) stacks (Section 4.2, Figs 10–12)
#
# Every mass but the top is at rest after the cascade. With one restitution `e` everywhere:
#
# * ratios `r_{i+1,i} = S_i/(1 + S_{i+1})`, `S_i = Σ_{k=1}^{i} e^k` (Eq 25); `i/(i+2)` for `e = 1`
#   (Eq 26); `(e^{i+1} − e)/(e^{i+2} − 1)` for `e < 1` (Eq 27); `→ e` as `i → ∞` (Eq 28);
# * gain `G_n = Σ_{k=1}^{n} e^k` (Eq 29), limit `e/(1 − e)` (Eq 30).
#
# Each statement is checked against the printed sums (typed in here) and against an independent
# event-by-event cascade of Eqs 1–2.

# %%
import numpy as np
import matplotlib.pyplot as plt

from _nbutil import QUICK, show, write_table
from hertz_chain import rigid

N = 10
ES = (0.5, 0.6, 0.7, 0.8, 0.9, 0.95, 1.0)


def S(e, i):
    return sum(e**k for k in range(1, i + 1))


def ratio_eq25(e, i):
    return S(e, i) / (1 + S(e, i + 1))


def cascade(masses, e):
    """Independent cascade of a dropped stack (v = -1 for all, ground restitution e), Eqs 1-2."""
    m = np.asarray(masses, float)
    v = -np.ones(m.size)
    v[0] = e  # ground bounce
    after = np.empty(m.size)
    for k in range(m.size - 1):
        va, vb = v[k], v[k + 1]
        p = m[k] * va + m[k + 1] * vb
        Vb = (p + m[k] * e * (va - vb)) / (m[k] + m[k + 1])
        Va = Vb - e * (va - vb)
        after[k], v[k + 1] = Va, Vb
    after[-1] = v[-1]
    return v, after  # v[i]: velocity of mass i+1 just after it is struck; after: after it strikes the next


# %% [markdown]
# ## Fig 10 — the pair-wise ratios `r_{i,i−1}` against the mass number

# %%
fig, ax = plt.subplots(figsize=(7, 4.2))
for e in ES:
    r = rigid.met_ratios(e, N)
    assert np.allclose(r, [ratio_eq25(e, i) for i in range(1, N)], rtol=1e-13)  # Eq 25 (= Eq 26/27)
    if e == 1:
        assert np.allclose(r, [i / (i + 2) for i in range(1, N)], rtol=1e-14)  # Eq 26
    ax.plot(np.arange(2, N + 1), r, "o-", ms=3, label=f"e = {e}")
    if e < 1:
        ax.axhline(e, lw=0.5, ls=":", color=ax.lines[-1].get_color())
ax.set(xlabel="mass number i", ylabel="r_{i,i-1} = m_i / m_{i-1}", title="Reproduces Fig 10 (Eq 25); dotted: the limit e (Eq 28)")
ax.legend(fontsize=7, ncol=2)
show(fig, "fig10_met_ratios")

for e in (0.5, 0.8, 0.95):
    assert np.isclose(rigid.met_ratios(e, 1000)[-1], e, rtol=1e-12)  # Eq 28: r -> e
    assert np.all(np.diff(rigid.met_ratios(e, 30)) > 0)  # the ratios rise towards e

# %% [markdown]
# ## The MET property: all masses but the top at rest after the cascade

# %%
for e in ES:
    m = rigid.met_masses(e, N)
    hit, after = cascade(m, e)
    assert np.max(np.abs(after[:-1])) < 1e-12  # Section 4.2: every mass but m_n comes to rest
    assert np.allclose(hit, [S(e, i) for i in range(1, N + 1)], rtol=1e-12)  # V_i = S_i v_ff
    h2, a2 = rigid.cascade_velocities(m, e, ground_restitution=e)
    assert np.allclose(h2, hit, rtol=1e-12) and np.allclose(a2, after, atol=1e-12)

# %% [markdown]
# ## Fig 11 — MET gain against e, n = 2 … 10 (Eq 29), and its limit (Eq 30)

# %%
eg = np.linspace(0.3 if QUICK else 0.2, 1.0, 30 if QUICK else 161)
fig, ax = plt.subplots(figsize=(7, 4.2))
for n in range(2, N + 1):
    G = rigid.met_gain(eg, n)
    assert np.allclose(G, [S(e, n) for e in eg], rtol=1e-12)  # Eq 29
    ax.plot(eg, G, label=f"n = {n}")
ax.plot(eg[eg < 0.92], rigid.met_gain_limit(eg[eg < 0.92]), "k--", label="n → ∞ (Eq 30)")
ax.axhline(1, color="grey", lw=0.5)
ax.set(xlabel="e", ylabel="G_n = V_n / v_ff", title="Reproduces Fig 11 (Eq 29)")
ax.legend(fontsize=7, ncol=2)
show(fig, "fig11_met_gain")

assert rigid.met_gain(1.0, 7) == 7  # Eq 29, e = 1: G_n = n
# Eq 30: G_max = e/(1-e) > 1 only for e > 1/2 ("velocity gain is only achievable if e > 0.5")
assert rigid.met_gain_limit(0.5) == 1.0 and np.all(rigid.met_gain(0.5, np.arange(2, 50)) < 1)
assert np.isclose(rigid.met_gain(0.8, 400), 4.0, rtol=1e-12)  # Eq 30: 0.8/0.2
print("MET, e = 0.8, n = 10: G =", rigid.met_gain(0.8, 10))
assert np.isclose(rigid.met_gain(0.8, 10), 3.5705, atol=5e-5)  # Eq 29; docs/references.md, "Seed paper key numbers"

# %% [markdown]
# ## Fig 12 — `m_i/m_1` against the mass number; the `R = 0.1` example
#
# Paper: "determining the number of masses for a machine with `R = 0.1` – the nearest whole number is 4".
# The figure's `e` is not stated. With `e = 1` (Eq 26) `R_4 = (1/3)(2/4)(3/5) = 0.1` exactly; `n = 4`
# is also the nearest (in `ln R`) for every `e ≥ 0.7`, but `n = 3` for `e ≤ 0.6` — the example holds
# for high restitution only.

# %%
fig, ax = plt.subplots(figsize=(7, 4.2))
for e in ES:
    m = rigid.met_masses(e, N)
    ax.semilogy(np.arange(1, N + 1), m, "o-", ms=3, label=f"e = {e}")
ax.axhline(0.1, color="k", lw=0.7, ls="--", label="R = 0.1 (paper's example)")
ax.set(xlabel="mass number i", ylabel="m_i / m_1", title="Reproduces Fig 12 (Eq 25)")
ax.legend(fontsize=7, ncol=2)
show(fig, "fig12_met_masses")

assert np.isclose(rigid.met_mass_ratio(1.0, 4), 0.1, rtol=1e-14)  # Eq 26: R_4 = 1/10
n_for_01 = {e: rigid.met_n_for_ratio(0.1, e) for e in ES}
print("n for R = 0.1:", n_for_01)
assert all(n_for_01[e] == 4 for e in ES if e >= 0.7)  # Fig 12 example ("nearest whole number is 4")
assert n_for_01[0.5] == 3 and n_for_01[0.6] == 3  # ... but 3 for e <= 0.6

# %%
rows = []
for e in ES:
    r = rigid.met_ratios(e, N)
    m = rigid.met_masses(e, N)
    for i in range(1, N + 1):
        rows.append((e, i, float(r[i - 2]) if i >= 2 else float("nan"), float(m[i - 1]), float(rigid.met_gain(e, i)) if i >= 2 else float("nan")))
write_table("met_ratios", ["e", "i", "r_i_im1_eq25", "m_i_over_m1", "G_i_eq29"], rows,
            ["Seed paper Eqs 25-29 (Figs 10-12): MET stack with restitution e at every impact.",
             "r_i_im1 = m_i/m_(i-1) (NaN for i = 1); G_i = gain of an i-mass MET stack (NaN for i = 1). Dimensionless.",
             "Generated by notebooks/03_met_stacks.py"])

"""A design as a differentiable function: the numbers of some stack-file keys -> `(Stack, State)`.

`DesignMap(spec, slots)` takes a validated stack file (explicit masses) and the `keys.Slot`s to vary.
Called with one value per slot (SI units), it returns the `Stack` and initial `State` that `build` would
make of the file with those values written in, as JAX functions of the values, so that `jax.grad`,
`jax.vmap` and `jit` go through them. The contacts follow the design as `build` makes them follow it:

- each interface's law is rebuilt from its stiffness and its dimensionless damping (`chi`, `eta`,
  `zeta`, `xi`: `AbstractContactLaw.dimensionless_damping`) with the design's reduced masses
  (`stack.reduced_masses`) and, for the speed-dependent laws calibrated to a restitution without a
  `calibration_velocity`, the rigid model's approach speed of that interface (paper Eqs 1–2 down the
  cascade, as `build._approach_speeds`);
- a varied restitution passes through the law's own calibration (scipy, on the host) with its
  derivative by a central difference of that calibration (`_dimensionless`); a law given by its raw
  damping keeps it (Tsuji's effective mass still follows the masses).

At the file's own values it reproduces `build(spec)` (tested to round-off, `tests/test_optimize.py`).
"""

from __future__ import annotations

import dataclasses
import math
from functools import lru_cache

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from . import _config  # noqa: F401  (float64)
from .builder import _stiffness, build
from .contact import _LAW_CLASSES
from .errors import StackFileError
from .keys import Slot
from .registry import LAWS
from .stack import Stack, State, at_impact, reduced_masses, resting
from .stackfile import StackSpec

__all__ = ["DesignMap", "with_masses"]


def with_masses(spec: StackSpec, masses) -> StackSpec:
    """The spec with explicit `masses` (kg, bottom first) in place of its masses or design."""
    bodies = dataclasses.replace(spec.stack, masses=tuple(float(m) for m in masses), design=None)
    return dataclasses.replace(spec, stack=bodies)


@lru_cache(maxsize=None)
def _dimensionless(law: str, chi_map: str, clamp: bool):
    """`e -> d(e)` of a law as a JAX function: the value by the law's calibration on the host
    (`jax.pure_callback`), the derivative by a central difference of it (step 1e-6, one-sided at e = 1)."""
    cls = _LAW_CLASSES[law]

    def host(e):
        e = np.asarray(e, dtype=float)
        out = np.vectorize(lambda x: cls.dimensionless_damping(float(x), chi_map=chi_map, clamp=clamp))(e)
        return np.asarray(out, dtype=float).reshape(e.shape)

    @jax.custom_jvp
    def d(e):
        return jax.pure_callback(host, jax.ShapeDtypeStruct(jnp.shape(e), jnp.float64), e,
                                 vmap_method="sequential")

    @d.defjvp
    def _jvp(primals, tangents):
        (e,), (de,) = primals, tangents
        h = 1e-6
        hi = jnp.minimum(e + h, 1.0)
        lo = hi - 2 * h
        return d(e), (d(hi) - d(lo)) / (hi - lo) * de

    return d


def _approach_speeds(m, e, v0, ground: bool):
    """Rigid approach speed of every interface (paper Eqs 1–2 down the cascade; `build._approach_speeds`),
    JAX-traceable: `(n,)`, entry 0 the ground's."""
    n = m.shape[0]
    cur = -e[0] * v0[0] if ground else v0[0]
    speeds = [jnp.abs(v0[0]) if ground else jnp.asarray(jnp.nan)]
    for k in range(n - 1):
        speeds.append(cur - v0[k + 1])
        cur = v0[k + 1] - m[k] * (1 + e[k + 1]) * (v0[k + 1] - cur) / (m[k] + m[k + 1])
    return jnp.stack(speeds)


class DesignMap:
    """`x -> (Stack, State)` for the values `x` (SI, one per slot) of `slots` in the file `spec`.

    **Arguments:** `spec`, a `StackSpec` with explicit masses (`with_masses`); `slots`, the `keys.Slot`s
    to vary (`keys.resolve`). **Raises** `StackFileError` when a slot cannot vary in this file (a
    restitution on an elastic law or one given by its raw damping, a drop key on a chain without ground).
    """

    def __init__(self, spec: StackSpec, slots: tuple[Slot, ...], section: str = "optimize.vary"):
        built = build(spec)
        self.spec, self.slots, self.built = spec, tuple(slots), built
        m = np.asarray(built.masses, dtype=float)
        n = self.n = m.size
        self.ground = spec.has_ground
        self.interfaces = tuple(range(0 if self.ground else 1, n))
        self.contacts = {j: spec.contact_for(j) for j in self.interfaces}
        if spec.stack.end_force > 0 or spec.wall is not None:
            what = "stack.end_force" if spec.stack.end_force > 0 else "[wall]"
            raise StackFileError(f"{section}: this stack is held by {what} (a chain that never flies apart, run to "
                                 "t_max); optimize, sweep and fit do not support held chains yet (simulate does)")
        stiffness_varied = {j for s in slots if s.key == "contact.stiffness"
                            for j in (self.interfaces if s.index is None else (s.index,))}
        for j, cs in self.contacts.items():
            row = LAWS[cs.law]
            why = None
            if row.memory and section.startswith("optimize"):
                why = ("keeps a plastic memory, and optimize's gradients do not go through it yet; sweep and "
                       "fit (no gradients) support it")
            elif cs.law == "jackson-green" and j in stiffness_varied:
                why = "joins its fit where it meets Hertz, a point that moves with the stiffness; its stiffness " \
                      "cannot vary (run one file per stiffness)"
            elif row.params and not row.memory and cs.restitution is not None:
                why = "is calibrated to a restitution through its further parameters; give its damping instead"
            if why is not None:
                raise StackFileError(f"{section}: contact law {cs.law!r} (interface {j}) {why}")
        k = np.full(n, math.nan)
        for j, cs in self.contacts.items():
            k[j] = _stiffness(spec, cs, j, n)
        self.gravity = float(spec.drop.gravity)
        self.chain = spec.stack.velocities is not None
        v = spec.drop.impact_velocity
        self.base = {
            "stack.masses": m,
            "stack.gaps": np.asarray(spec.stack.gap_list(n), dtype=float) if n > 1 else np.zeros(0),
            "contact.stiffness": k,
            "contact.restitution": np.asarray(built.nominal_restitution, dtype=float),
            "drop.impact_velocity": np.asarray(math.nan if v is None else v),
            "drop.height": np.asarray(math.nan if v is None or self.gravity <= 0 else v * v / (2 * self.gravity)),
        }
        self.section = section
        for s in self.slots:
            self._check(s)
        if {"drop.height", "drop.impact_velocity"} <= {s.key for s in self.slots}:
            raise StackFileError(f"{self.section}: drop.height and drop.impact_velocity both set the drop speed; "
                                 "vary one of them")
        self._d = {j: _LAW_CLASSES[cs.law].dimensionless_damping(cs.restitution, chi_map=cs.chi_map or "exact",
                                                                 clamp=cs.clamp)
                   for j, cs in self.contacts.items() if not LAWS[cs.law].elastic and cs.restitution is not None}

    def _check(self, s: Slot) -> None:
        where = f"{self.section}: {s.label}"
        if s.key.startswith("drop.") and (self.chain or not self.ground):
            raise StackFileError(f"{where}: this stack starts from stack.velocities; there is no drop to vary")
        if s.key == "drop.height" and self.gravity <= 0:
            raise StackFileError(f"{where}: a drop height needs gravity, but drop.gravity = 0; vary "
                                 "drop.impact_velocity")
        if s.key == "contact.restitution":
            cs = self.contacts[s.index]
            if LAWS[cs.law].elastic or cs.restitution is None:
                why = ("is elastic" if LAWS[cs.law].elastic else "is plastic (e follows from its yield parameters "
                       "and the impact speed)" if LAWS[cs.law].memory else "is given by its raw damping")
                raise StackFileError(f"{where}: interface {s.index}'s law {cs.law!r} {why}; it has no "
                                     "restitution to vary")

    def values(self) -> np.ndarray:
        """The file's own values of the slots (SI)."""
        return np.array([float(self.base[s.key] if s.index is None else self.base[s.key][s.position])
                         for s in self.slots])

    def fields(self, x) -> dict:
        """Every varied key's array with the values `x` written in (JAX)."""
        x = jnp.asarray(x, dtype=float)
        out = {key: jnp.asarray(v) for key, v in self.base.items()}
        for i, s in enumerate(self.slots):
            out[s.key] = out[s.key].at[s.position].set(x[i]) if s.index is not None else x[i]
        if any(s.key == "drop.height" for s in self.slots):
            out["drop.impact_velocity"] = jnp.sqrt(2.0 * self.gravity * out["drop.height"])
        return out

    def __call__(self, x) -> tuple[Stack, State]:
        f = self.fields(x)
        m, k, e = f["stack.masses"], f["contact.stiffness"], f["contact.restitution"]
        varied_e = {s.index for s in self.slots if s.key == "contact.restitution"}
        m_eff = reduced_masses(m)
        if self.chain:
            v0 = jnp.asarray(self.spec.initial_velocities(self.n), dtype=float)
        else:
            v0 = jnp.broadcast_to(-f["drop.impact_velocity"], (self.n,))
        speeds = _approach_speeds(m, jnp.where(jnp.isfinite(e), e, 1.0), v0, self.ground)
        laws = []
        for j, cs in self.contacts.items():
            base_law = self.built.laws[j]
            cls = type(base_law)
            if cs.law == "thornton":  # delta_y = R (pi p_y / 2E*)^2 with E* ~ k: delta_y ~ 1/k^2 at fixed p_y, R
                law = eqx.tree_at(lambda law: (law.k, law.delta_y), base_law,
                                  (k[j], base_law.delta_y * (base_law.k / k[j]) ** 2))
            elif LAWS[cs.law].memory:  # jackson-green: its stiffness is not varied (checked above)
                law = base_law
            elif LAWS[cs.law].elastic or cs.restitution is None:
                law = eqx.tree_at(lambda law: law.k, base_law, k[j])
                if hasattr(law, "m_eff"):
                    law = eqx.tree_at(lambda law: law.m_eff, law, m_eff[j])
            else:
                d = (_dimensionless(cs.law, cs.chi_map or "exact", cs.clamp)(e[j]) if j in varied_e
                     else self._d[j])
                v_c = cs.calibration_velocity if cs.calibration_velocity is not None else speeds[j]
                law = cls.from_dimensionless(k[j], d, effective_mass=m_eff[j], calibration_velocity=v_c,
                                             clamp=cs.clamp)
            laws.append(law)
        stack = Stack(m, laws, gravity=self.gravity, ground=self.ground)
        if self.chain:
            x0 = jnp.concatenate([jnp.zeros(1), jnp.cumsum(f["stack.gaps"])])
            return stack, State(x0, v0)
        v = f["drop.impact_velocity"]
        if self.spec.stack.preload:
            return stack, resting(stack, height=v**2 / (2 * self.gravity))
        return stack, at_impact(stack, v, f["stack.gaps"])

    def drop_speed(self, x):
        """The reference speed of the gains: the impact velocity (or the largest initial speed of a chain)."""
        if self.chain:
            return float(np.max(np.abs(self.spec.initial_velocities(self.n))))
        return self.fields(x)["drop.impact_velocity"]

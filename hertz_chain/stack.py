"""The stack as a dynamical system: masses, one contact law per interface, ground, gravity.

A `Stack` is an `eqx.Module` whose numbers (masses, gravity, every contact parameter) are array
leaves, so `jax.vmap`, `jax.grad` and `eqx.filter_vmap` work over designs. The structure (number of
masses, law types, presence of the ground) is static: one compiled solver serves every design of one
structure.

Conventions (`notes/CONVENTIONS.md`): masses numbered from the bottom (index 0 is mass 1), positions
`x_i` upward with sizes absorbed (`x_1 = 0` when mass 1 touches the ground, `x_{i+1} - x_i` is the
gap), interface 0 is ground–mass 1, interface `j` is mass `j` – mass `j+1`; the overlap of interface 0
is `delta_0 = -x_1`, of interface `j` it is `delta_j = x_j - x_{j+1}`; `delta > 0` is compression.

The state vector used by the vector field is flat, in SI units:
`y = [x_1..x_n, v_1..v_n, D_0..D_{n-1}]`, where `D_j` is the energy dissipated so far by interface `j`
(J), integrated from `P_j = (F_j - F^el_j) * delta_dot_j >= 0`, so that the energy audit
`kinetic + gravitational + elastic + dissipated = initial energy` can be checked on every step.

Initial states (`State`): `at_impact` (a), `dropped` (b), `resting` (c), or `State(x, v)` (d).
All builders are JAX-traceable (they may be vmapped and differentiated with respect to gaps, masses and
contact parameters).
"""

from __future__ import annotations

from collections.abc import Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike

from . import _config  # noqa: F401  (float64)
from .contact import AbstractContactLaw
from ._fusion import materialised
from .constants import MAX_MASSES, STANDARD_GRAVITY
from .errors import ParameterError

__all__ = [
    "STANDARD_GRAVITY",
    "Stack",
    "State",
    "at_impact",
    "dropped",
    "resting",
    "precompressed",
    "stack_designs",
    "invert_monotone",
    "reduced_masses",
]



def reduced_masses(masses: ArrayLike) -> Array:
    """`(..., n)` reduced (effective) mass of every interface of a stack with masses `(..., n)`: entry 0
    is the ground's, `m_1` (the ground is immovable), entry j is `m_j m_{j+1}/(m_j + m_{j+1})`.
    JAX-traceable; the one home of this formula."""
    m = jnp.asarray(masses, dtype=float)
    pair = m[..., :-1] * m[..., 1:] / (m[..., :-1] + m[..., 1:])
    return jnp.concatenate([m[..., :1], pair], axis=-1)


def _is_concrete(*xs) -> bool:
    return not any(isinstance(x, jax.core.Tracer) for x in jax.tree.leaves(xs))


def _traced_rule(a: Array, ok: Array, name: str, allowed: str) -> Array:
    """`a` with its rule (`ok`) checked where it is traced, as a concrete value is checked at once:
    `ParameterError` where the value is known (plain `jax.grad`/`jax.jacfwd`); under the caller's
    `jit`/`vmap`, `a` made NaN where it breaks the rule, so that the state is not finite and
    `launch_velocity`'s guard after the solve raises (no host callback in the compiled solve)."""
    try:
        known_bad = not bool(jnp.all(ok))
    except jax.errors.ConcretizationTypeError:  # under jit or vmap: checked when it runs
        return jnp.where(ok, a, jnp.nan)
    if known_bad:
        raise ParameterError(name, _primal(a), f"{allowed} (a traced value, under jax.grad or jax.jacfwd)")
    return a


def _primal(a):
    """The value under a traced `a` where the trace carries it (plain `jax.grad`/`jax.jacfwd`), for
    messages; "traced" otherwise."""
    while isinstance(a, jax.core.Tracer) and hasattr(a, "primal"):
        a = a.primal
    if isinstance(a, jax.core.Tracer):
        return "traced"
    v = np.asarray(a)
    return float(v) if v.ndim == 0 else v.tolist()


def _real_array(value: ArrayLike, name: str, shape: tuple | None = None) -> Array:
    """`value` as a float array, or `ParameterError` naming `name` for what is not numbers (a string, a
    complex number; `shape`: the one shape allowed)."""
    if _is_concrete(value):  # (a list may hold tracers: a differentiable stack written [m1, m2])
        try:
            a = np.asarray(value)
        except (TypeError, ValueError):
            a = np.asarray(None)
        if a.dtype.kind in "USOcM" or a.dtype == object:  # strings, objects, complex, dates (bfloat16: "V")
            raise ParameterError(name, value, "real numbers (SI units; quantity strings belong to stack files)")
    out = jnp.asarray(value, dtype=float)
    if shape is not None and out.shape != shape:
        raise ParameterError(name, f"shape {np.shape(value)}", "a single number" if shape == () else f"shape {shape}")
    return out


def _group_laws(laws: Sequence[AbstractContactLaw], interfaces: Sequence[int]):
    """Group per-interface laws by pytree structure (type and static config) and stack each group."""
    groups: dict = {}
    for j, law in zip(interfaces, laws):
        if not isinstance(law, AbstractContactLaw):
            raise ParameterError(f"laws[{j}]", law, "an AbstractContactLaw (hertz_chain.contact)")
        for leaf in jax.tree.leaves(law):
            if jnp.ndim(leaf) != 0:
                raise ParameterError(
                    f"laws[{j}]", law, "per-interface laws with scalar parameters (or one law with "
                    "parameters of shape (n_interfaces,))"
                )
        groups.setdefault(jax.tree.structure(law), []).append((j, law))
    idx, stacked = [], []
    for members in groups.values():
        idx.append(tuple(j for j, _ in members))
        stacked.append(jax.tree.map(lambda *x: jnp.stack(x), *[law for _, law in members]))
    return tuple(stacked), tuple(idx)


class Stack(eqx.Module):
    """A stack (or horizontal chain) of `n` point masses joined by compliant contacts.

    **Arguments:**

    - `masses`: `(n,)` masses in kg, numbered from the bottom, `1 <= n <= 1000` (`constants.MAX_MASSES`; `n = 1` needs the ground).
    - `laws`: the contact law of every interface. Either one law (used for every interface; its
      parameters are scalars, or arrays of shape `(n_interfaces,)` for one value per interface), or a
      sequence with one law per interface: length `n` with the ground (entry 0 is ground–mass 1), length
      `n - 1` without it (interfaces 1..n-1; a leading `None` for interface 0 is also accepted). Laws of
      different types may be mixed; laws of one type are vectorised together.
    - `gravity`: gravitational acceleration in m/s² (default standard gravity), `>= 0`; acts downward.
    - `ground`: whether interface 0 (a rigid, immovable ground at `x = 0`) exists. Without it the stack is
      the free chain of the paper's Section 3.
    - `end_force`: a constant force `F0 >= 0` (N) on the top mass, pushing it toward mass 1 (downward),
      as a dead weight or a preloaded spring at the far end of a granular chain does (default 0). It
      needs the ground (something must hold the chain against it). `resting` puts such a chain in
      static equilibrium (every contact carries `F0` plus the weight above it: a precompressed chain).
      A chain held by an end force never flies apart: simulate it with `until="t_max"`.
    - `wall_stiffness`, `wall_position`: a rigid wall beyond the top mass (the far end of a chain between
      two walls): an elastic Hertz contact `F_w = k_w <x_n - x_w>^{3/2}` (N) pushing the top mass down,
      `k_w` in N/m^1.5 (`materials.contact_stiffness` of the top mass on a flat), `x_w` (m) the wall's
      face in the top mass's coordinate. Both or neither (default: no wall). A chain with a wall is
      held too (`until="t_max"`); `precompressed` places the wall for a static precompression.

    Laws of one type are stored as one vectorised law (`laws[g]` serves the interfaces `groups[g]`), so the
    vector field costs one call per law type, whatever `n`.
    """

    masses: Array
    laws: tuple[AbstractContactLaw, ...]
    gravity: Array
    end_force: Array
    wall_stiffness: Array
    wall_position: Array
    ground: bool = eqx.field(static=True)
    wall: bool = eqx.field(static=True)
    groups: tuple[tuple[int, ...], ...] = eqx.field(static=True)

    def __init__(
        self,
        masses: ArrayLike,
        laws: AbstractContactLaw | Sequence[AbstractContactLaw | None],
        *,
        gravity: ArrayLike = STANDARD_GRAVITY,
        ground: bool = True,
        end_force: ArrayLike = 0.0,
        wall_stiffness: ArrayLike | None = None,
        wall_position: ArrayLike | None = None,
    ):
        masses = _real_array(masses, "masses")
        gravity = _real_array(gravity, "gravity", shape=())
        end_force = _real_array(end_force, "end_force", shape=())
        if masses.ndim != 1:
            raise ParameterError("masses", masses, "a 1-D array of masses (kg), bottom first")
        n = masses.shape[0]
        if not 1 <= n <= MAX_MASSES:
            raise ParameterError("len(masses)", n, f"between 1 and {MAX_MASSES} masses")
        if not isinstance(ground, (bool, np.bool_)):  # a string such as "false" would read as True
            raise ParameterError("ground", ground, "True or False")
        if n == 1 and not ground:
            raise ParameterError("ground", ground, "True for a single mass (it needs something to hit)")
        if _is_concrete(masses, gravity):
            m = np.asarray(masses)
            if not np.all(np.isfinite(m) & (m > 0)):
                raise ParameterError("masses", m.tolist(), "finite and > 0 (kg)")
            g = float(gravity)
            if not (np.isfinite(g) and g >= 0):
                raise ParameterError("gravity", g, "finite and >= 0 (m/s², acting downward)")
        if _is_concrete(end_force):
            f0 = np.asarray(end_force)
            if f0.ndim != 0 or not (np.isfinite(f0) and f0 >= 0):
                raise ParameterError("end_force", f0.tolist(), "a finite number >= 0 (N, pushing the top mass "
                                     "toward mass 1)")
            if float(f0) > 0 and not ground:
                raise ParameterError("end_force", float(f0), "0 without the ground (nothing holds the chain "
                                     "against it)")
        if (wall_stiffness is None) != (wall_position is None):
            raise ParameterError("wall_position" if wall_position is None else "wall_stiffness", None,
                                 "given together with the other (a far wall needs its stiffness and position)")
        wall = wall_stiffness is not None
        if wall and not ground:  # as the stack file's [wall]: the analysis takes a walled chain as held
            raise ParameterError("wall_stiffness", "given with ground=False", "a far wall only with the ground "
                                 "(ground=True): it closes a chain between the ground at mass 1 and the wall")
        wall_stiffness = jnp.asarray(0.0 if wall_stiffness is None else wall_stiffness, dtype=float)
        wall_position = jnp.asarray(0.0 if wall_position is None else wall_position, dtype=float)
        if wall and _is_concrete(wall_stiffness, wall_position):
            kw, xw = np.asarray(wall_stiffness), np.asarray(wall_position)
            if kw.ndim or not (np.isfinite(kw) and kw > 0):
                raise ParameterError("wall_stiffness", kw.tolist(), "a finite number > 0 (N/m^1.5)")
            if xw.ndim or not np.isfinite(xw):
                raise ParameterError("wall_position", xw.tolist(), "a finite number (m)")
        interfaces = list(range(0 if ground else 1, n))
        if isinstance(laws, AbstractContactLaw):
            shapes = {jnp.shape(leaf) for leaf in jax.tree.leaves(laws)}
            if shapes <= {()}:
                laws = jax.tree.map(lambda a: jnp.broadcast_to(a, (len(interfaces),)), laws)
            elif shapes != {(len(interfaces),)}:
                raise ParameterError(
                    "laws", laws, f"scalar parameters or parameters of shape ({len(interfaces)},)"
                )
            stacked, groups = (laws,), (tuple(interfaces),)
        else:
            if isinstance(laws, (str, bytes)) or not hasattr(laws, "__len__"):
                raise ParameterError("laws", laws, "a contact law (e.g. hertz_chain.Hertz(1e9)) or one per interface; "
                                     "hertz_chain.make_law builds one from its name")
            laws = list(laws)
            if not ground and len(laws) == n and laws and laws[0] is None:
                laws = laws[1:]
            if len(laws) != len(interfaces):
                raise ParameterError(
                    "laws", f"{len(laws)} laws", f"one law per interface: {len(interfaces)} for n = {n}"
                    f" {'with' if ground else 'without'} the ground"
                    + ("" if ground or len(laws) != n else " (or n with None first, where the ground would be)")
                )
            stacked, groups = _group_laws(laws, interfaces)
        self.masses = masses
        self.laws = stacked
        self.gravity = gravity
        self.end_force = end_force
        self.wall_stiffness = wall_stiffness
        self.wall_position = wall_position
        self.ground = bool(ground)
        self.wall = wall
        self.groups = groups

    # ---------------------------------------------------------------- structure
    @property
    def n(self) -> int:
        """Number of masses."""
        return self.masses.shape[-1]

    @property
    def interfaces(self) -> tuple[int, ...]:
        """The interfaces that exist (0..n-1 with the ground, 1..n-1 without)."""
        return tuple(range(0 if self.ground else 1, self.n))

    def effective_masses(self) -> Array:
        """`(n,)` reduced mass of every interface (`reduced_masses`)."""
        return reduced_masses(self.masses)

    def interface_mask(self) -> Array:
        """`(n,)` booleans: which interfaces exist (entry 0 is False without the ground)."""
        return jnp.asarray([self.ground] + [True] * (self.n - 1))

    def clamped(self) -> np.ndarray:
        """`(n,)` static booleans: which interfaces use the no-tension clamp (`law.clamp`).

        A clamped contact is open once its force is zero (it may let go at `delta > 0`); an unclamped
        one (tensile force allowed while `delta > 0`) is open once `delta <= 0`. Entry 0 is True
        without the ground (no interface there).
        """
        out = np.ones(self.n, dtype=bool)
        for idx, law in zip(self.groups, self.laws):
            out[list(idx)] = bool(getattr(law, "clamp", True))
        return out

    def law_of(self, j: int) -> AbstractContactLaw:
        """The (scalar) contact law of interface `j`."""
        for idx, law in zip(self.groups, self.laws):
            if j in idx:
                k = idx.index(j)
                return jax.tree.map(lambda a: a[k], law)
        raise ParameterError("interface", j, f"one of {self.interfaces}")

    # ---------------------------------------------------------------- per-interface evaluation
    @property
    def has_memory(self) -> bool:
        """Some law keeps an internal variable per interface (`AbstractContactLaw.has_memory`): the state
        is then `[x, v, D, q]` (`4n`), `q` the largest overlap of every interface so far."""
        return any(type(law).has_memory for law in self.laws)

    @property
    def state_size(self) -> int:
        """Length of the flat SI state: `3n` (`[x, v, D]`), `4n` with a law with memory (`[x, v, D, q]`)."""
        return (4 if self.has_memory else 3) * self.n

    def memory(self, y: Array) -> Array | None:
        """`(..., n)` the memory block `q` of a flat state (largest overlaps, m), None without memory laws."""
        n = self.n
        return y[..., 3 * n : 4 * n] if self.has_memory else None

    def initial_vector(self, state: "State") -> Array:
        """The flat SI state `[x, v, D = 0 (, q)]` of `state` (`state_size` entries); a law with memory's
        `q` (its largest overlap so far) starts at the initial overlaps (`_plastic._ElasticPlastic.memory_rate`:
        it follows the overlap through the approach, so that nothing switches at the onset)."""
        y = state.flat()
        if not self.has_memory:
            return y
        return jnp.concatenate([y, self.overlaps(jnp.asarray(state.positions, dtype=float))], axis=-1)

    def _map_laws(self, fn, *args: Array, q: Array | None = None) -> Array:
        """Apply `fn(law, *args_of_its_interfaces, q_of_its_interfaces)` group-wise (`q` is None for a law
        without memory, or when no `q` is given); zero on missing interfaces. Stacked states `(..., n)` are
        mapped row by row (`jax.vmap`): a law sees one state's interfaces at a time, never an implicit
        broadcast of its `(n_group,)` parameters against rows."""
        n = self.n
        if jnp.ndim(self.masses) > 1:  # a batch of designs (`stack_designs`) called directly: design by design
            return eqx.filter_vmap(lambda st, qq, *r: st._map_laws(fn, *r, q=qq),
                                   in_axes=(eqx.if_array(0), None if q is None else 0) + (0,) * len(args))(
                self, q, *args)
        if jnp.ndim(args[0]) > 1:
            lead = jnp.shape(args[0])[:-1]
            rows = [jnp.reshape(jnp.asarray(a, dtype=float), (-1, n)) for a in args]
            if q is None:
                out = jax.vmap(lambda *r: self._map_laws(fn, *r))(*rows)
            else:
                q_rows = jnp.reshape(jnp.asarray(q, dtype=float), (-1, n))
                out = jax.vmap(lambda qq, *r: self._map_laws(fn, *r, q=qq))(q_rows, *rows)
            return jnp.reshape(out, lead + (n,))
        out = jnp.zeros(jnp.shape(args[0]), dtype=float)
        for idx, law in zip(self.groups, self.laws):
            mem = type(law).has_memory and q is not None
            if idx == tuple(range(n)):
                return fn(law, *args, q if mem else None)
            start, stop = idx[0], idx[-1] + 1
            if idx == tuple(range(start, stop)):  # contiguous: a slice
                sl = slice(start, stop)
            else:
                sl = np.asarray(idx)
            out = out.at[..., sl].set(fn(law, *(a[..., sl] for a in args), q[..., sl] if mem else None))
        return out

    def overlaps(self, x: Array) -> Array:
        """`(..., n)` overlaps `delta` of every interface from positions (entry 0 is 0 without ground)."""
        d0 = -x[..., :1] if self.ground else jnp.zeros_like(x[..., :1])
        return jnp.concatenate([d0, x[..., :-1] - x[..., 1:]], axis=-1)

    def overlap_rates(self, v: Array) -> Array:
        """`(..., n)` overlap rates `delta_dot` (> 0 while approaching)."""
        return self.overlaps(v)

    # `q` (the memory block, `memory`) reaches the laws with memory only; without it they behave as on
    # their first loading.
    def forces(self, delta: Array, delta_dot: Array, q: Array | None = None) -> Array:
        """`(..., n)` contact force of every interface (N, >= 0 pushes apart)."""
        return self._map_laws(lambda law, d, dd, m: law.force(d, dd) if m is None else law.force(d, dd, m),
                              delta, delta_dot, q=q)

    def elastic_forces(self, delta: Array, q: Array | None = None) -> Array:
        """`(..., n)` conservative part of every contact force (N)."""
        return self._map_laws(lambda law, d, m: law.elastic_force(d) if m is None else law.elastic_force(d, m),
                              delta, q=q)

    def unclamped_forces(self, delta: Array, delta_dot: Array, q: Array | None = None) -> Array:
        """`(..., n)` `elastic_force + damping_force`, without the no-tension clamp (N)."""
        return self.elastic_forces(delta, q) + self._map_laws(
            lambda law, d, dd, m: law.damping_force(d, dd), delta, delta_dot)

    def potentials(self, delta: Array, q: Array | None = None) -> Array:
        """`(..., n)` elastic (recoverable) energy stored in every contact (J)."""
        return self._map_laws(lambda law, d, m: law.potential(d) if m is None else law.potential(d, m),
                              delta, q=q)

    def dissipated_powers(self, delta: Array, delta_dot: Array, q: Array | None = None) -> Array:
        """`(..., n)` power dissipated by every contact (W; `AbstractContactLaw.dissipated_power`)."""
        return self._map_laws(
            lambda law, d, dd, m: law.dissipated_power(d, dd) if m is None else law.dissipated_power(d, dd, m),
            delta, delta_dot, q=q)

    def memory_rates(self, delta: Array, delta_dot: Array, q: Array) -> Array:
        """`(..., n)` `dq/dt` of the memory block (0 on interfaces whose law has no memory)."""
        return self._map_laws(lambda law, d, dd, m: jnp.zeros_like(d) if m is None else law.memory_rate(d, dd, m),
                              delta, delta_dot, q=q)

    def separation_function(self, delta: Array, delta_dot: Array, q: Array | None = None) -> Array:
        """`(..., n)` a function that is `> 0` exactly while a contact pushes, `<= 0` once it is open.

        `G = (F^el + F^damp) delta / F^el` for `delta > 0` (the unclamped force over the secant
        stiffness: a length, smooth through the force zero; `G = delta` for an elastic law), and
        `G = delta` otherwise. With the no-tension clamp the bodies separate at `G = 0` (force zero),
        possibly at `delta > 0`. Without it (`law.clamp=False`) the contact pulls until the overlap
        closes, so `G = delta` on that interface. An elastic–plastic law: `G = delta - delta_p`, the
        overlap above the permanent one (`AbstractContactLaw.separation`). Used to locate the end of
        contacts.
        """
        return self._map_laws(lambda law, d, dd, m: law.separation(d, dd) if m is None else law.separation(d, dd, m),
                              delta, delta_dot, q=q)

    def in_contact(self, delta: Array, delta_dot: Array, q: Array | None = None, forces: Array | None = None) -> Array:
        """`(..., n)` booleans: the contact is closed (force > 0 if clamped, `delta > 0` if not). `forces`:
        `forces(delta, delta_dot, q)`, where the caller has them."""
        f = self.forces(delta, delta_dot, q) if forces is None else forces
        return jnp.where(self.clamped(), f > 0, delta > 0)

    @property
    def held(self) -> bool:
        """The chain is held at its far end (an end force or a wall; concrete stacks only): it never flies
        apart, so it is simulated to `t_max`."""
        return self.wall or bool(np.asarray(self.end_force).any())  # (!= 0, NaN included; ~2 us)

    def wall_overlap(self, x: Array) -> Array:
        """`(...)` overlap of the top mass with the far wall, `x_n - x_w` (m; <= 0 when apart)."""
        return x[..., -1] - self.wall_position

    def wall_force(self, x: Array) -> Array:
        """`(...)` force of the far wall on the top mass (N, >= 0 pushes it down; 0 without a wall)."""
        if not self.wall:
            return jnp.zeros_like(x[..., -1])
        d = self.wall_overlap(x)
        d = jnp.where(d > 0, d, 0.0)  # zero force and zero gradient while apart
        return self.wall_stiffness * d**1.5

    def wall_potential(self, x: Array) -> Array:
        """`(...)` elastic energy of the far wall's contact, `(2/5) k_w <x_n - x_w>^{5/2}` (J)."""
        if not self.wall:
            return jnp.zeros_like(x[..., -1])
        d = self.wall_overlap(x)
        d = jnp.where(d > 0, d, 0.0)
        return 0.4 * self.wall_stiffness * d**2.5

    def accelerations(self, forces: Array, x: Array | None = None, inv_masses: Array | None = None) -> Array:
        """`(..., n)` accelerations of the masses (m/s², upward) from the interface forces, gravity, the
        end force and (from the positions `x`, needed with a wall) the far wall's force on the top mass.
        `inv_masses`: `1 / masses`, where the caller computed it once (a multiplication instead of a
        division per call, equal to rounding)."""
        top = jnp.broadcast_to(self.end_force[..., None], forces[..., :1].shape)
        if self.wall:
            if x is None:
                raise ParameterError("x", None, "the positions, for the far wall's force")
            top = top + self.wall_force(x)[..., None]
        above = jnp.concatenate([forces[..., 1:], top], axis=-1)
        if inv_masses is not None:
            return (forces - above) * inv_masses - self.gravity
        return (forces - above) / self.masses - self.gravity

    # ---------------------------------------------------------------- dynamics
    def split(self, y: Array) -> tuple[Array, Array, Array]:
        """Split a flat state `(..., 3n)` (or `(..., 4n)`, `memory`) into positions, velocities and
        dissipated energies."""
        n = self.n
        return y[..., :n], y[..., n : 2 * n], y[..., 2 * n : 3 * n]

    def vector_field(self, t, y: Array, args=None) -> Array:
        """`dy/dt` of the flat SI state `y = [x, v, D (, q)]` (diffrax signature `(t, y, args)`).

        `dx/dt = v`; `m_i dv_i/dt = F_{i-1,i} - F_{i,i+1} - m_i g` (Newton); `dD_j/dt = (F_j -
        F^el_j) delta_dot_j`, the power dissipated by the damping part of interface `j` (with the
        no-tension clamp, `F_j = 0` while `F^el_j > 0` on separation, which also dissipates); with a
        law with memory, its own `dissipated_power` and `dq_j/dt = memory_rate` (`Thornton`).
        """
        return self.vector_field_and_forces(t, y)[0]

    def vector_field_and_forces(self, t, y: Array, inv_masses: Array | None = None) -> tuple[Array, Array]:
        """`vector_field(t, y)` and the `(..., n)` contact forces (N) it used (one evaluation of the
        laws; the solver's onset proxy reads the forces, `hertz_chain._solve._scaled_field`).
        `inv_masses`: as in `accelerations`."""
        x, v, _ = self.split(y)
        q = self.memory(y)
        d, dd = self.overlaps(x), self.overlap_rates(v)
        f = self.forces(d, dd, q)
        if q is None:  # the common path: the damping part's power, from the forces at hand
            # one kernel for the forces in a vmapped solve, not one evaluation per element that reads them
            f, fel = materialised(f, self.elastic_forces(d))
            return jnp.concatenate([v, self.accelerations(f, x, inv_masses), (f - fel) * dd],
                                   axis=-1), f
        parts = [v, self.accelerations(f, x, inv_masses), self.dissipated_powers(d, dd, q), self.memory_rates(d, dd, q)]
        return jnp.concatenate(parts, axis=-1), f

    def energies(self, y: Array) -> dict[str, Array]:
        """Kinetic, gravitational (zero at `x = 0`; with the end force's potential `F0 x_n`), elastic and
        dissipated energy (J) of a state."""
        x, v, diss = self.split(y)
        return dict(
            kinetic=0.5 * jnp.sum(self.masses * v**2, axis=-1),
            gravitational=self.gravity * jnp.sum(self.masses * x, axis=-1) + self.end_force * x[..., -1],
            elastic=jnp.sum(self.potentials(self.overlaps(x), self.memory(y)), axis=-1) + self.wall_potential(x),
            dissipated=jnp.sum(diss, axis=-1),
        )

    def total_energy(self, y: Array) -> Array:
        """Sum of the four energies of `energies` (J): constant along an exact trajectory.

        Written as one reduction over the concatenated terms rather than the sum of `energies`:
        it is evaluated inside the solver loop by the energy audit, where each reduction is a
        separate XLA loop operation.
        """
        x, v, diss = self.split(y)
        mech = self.masses * (0.5 * v**2 + self.gravity[..., None] * x)
        mech = mech.at[..., -1].add(self.end_force * x[..., -1] + self.wall_potential(x))
        return jnp.sum(jnp.concatenate([mech, self.potentials(self.overlaps(x), self.memory(y)), diss], axis=-1),
                       axis=-1)


def stack_designs(stacks: Sequence[Stack]) -> Stack:
    """Stack a list of designs of one structure into one batched `Stack` (leading axis = design)."""
    stacks = list(stacks)
    structs = {jax.tree.structure(s) for s in stacks}
    if len(structs) != 1:
        raise ParameterError("stacks", f"{len(structs)} structures", "designs of one structure "
                             "(same n, law types, ground)")
    return jax.tree.map(lambda *x: jnp.stack(x), *stacks)


# ==================================================================== initial states
class State(eqx.Module):
    """Positions (m, upward) and velocities (m/s, upward) of every mass: initial state (d)."""

    positions: Array
    velocities: Array

    def __init__(self, positions: ArrayLike, velocities: ArrayLike):
        self.positions = _real_array(positions, "positions")
        self.velocities = _real_array(velocities, "velocities")
        if self.positions.shape != self.velocities.shape or self.positions.ndim < 1:
            raise ParameterError("velocities", self.velocities.shape,
                                 f"the shape of positions {self.positions.shape}")
        for name, a in (("positions", self.positions), ("velocities", self.velocities)):
            if _is_concrete(a) and not np.all(np.isfinite(np.asarray(a))):
                raise ParameterError(name, np.asarray(a).tolist(), "finite numbers (m, m/s)")

    def flat(self) -> Array:
        """The flat SI state `[x, v, D = 0]` used by `Stack.vector_field`."""
        x, v = self.positions, self.velocities
        return jnp.concatenate([x, v, jnp.zeros_like(x)], axis=-1)


def _gaps(stack: Stack, gaps) -> Array:
    n = stack.n
    if gaps is None:
        return jnp.zeros(n - 1)
    g = jnp.asarray(gaps, dtype=float)
    if g.ndim == 0:
        g = jnp.broadcast_to(g, (n - 1,))
    if g.shape != (n - 1,):
        raise ParameterError("gaps", tuple(g.shape), f"a scalar or shape ({n - 1},): the gap between "
                             "mass j and j+1 (m)")
    if not _is_concrete(g):
        return _traced_rule(g, jnp.isfinite(g) & (g >= 0), "gaps", "finite and >= 0 (m)")
    if not np.all((np.asarray(g) >= 0) & np.isfinite(np.asarray(g))):
        raise ParameterError("gaps", np.asarray(g).tolist(), "finite and >= 0 (m)")
    return g


def at_impact(stack: Stack, velocity: ArrayLike, gaps: ArrayLike | None = None) -> State:
    """Initial state (a): mass 1 just touches the ground, every mass moves down at `velocity`.

    **Arguments:** `velocity` is the drop (free-fall) speed `v_ff >= 0` (m/s; 0: mass 1 rests on the
    ground and the others fall through their gaps onto it; with no gaps nothing falls, and the gains,
    ratios to `v_ff`, are undefined); `gaps` (m), a scalar or `(n-1,)`, finite and >= 0, the gap between
    the surfaces of masses `j` and `j+1` (default 0: touching, unloaded).
    Paper Section 4: "initially all the masses are approaching the ground with the same free-fall
    velocity `v_ff`".
    """
    v = _real_array(velocity, "velocity", shape=())
    if not _is_concrete(v):
        v = _traced_rule(v, jnp.isfinite(v) & (v >= 0), "velocity", "a finite drop speed >= 0 (m/s, downward)")
    elif not (np.isfinite(float(v)) and float(v) >= 0):
        raise ParameterError("velocity", float(v), "a finite drop speed >= 0 (m/s, downward)")
    g = _gaps(stack, gaps)
    x = jnp.concatenate([jnp.zeros(1), jnp.cumsum(g)])
    return State(x, jnp.broadcast_to(-v, x.shape))


def dropped(stack: Stack, height: ArrayLike, gaps: ArrayLike | None = None) -> State:
    """Initial state (b): dropped from rest at `height` (m) with rigid gaps: `at_impact` with
    `v_ff = sqrt(2 g h)` (free fall, the gaps unchanged since every mass falls alike)."""
    h = jnp.asarray(height, dtype=float)
    if not _is_concrete(h):
        h = _traced_rule(h, jnp.isfinite(h) & (h >= 0), "height", "finite and >= 0 (m)")
    if _is_concrete(h, stack.gravity):
        if not (np.isfinite(float(h)) and float(h) >= 0):
            raise ParameterError("height", float(h), "finite and >= 0 (m)")
        if float(h) > 0 and float(stack.gravity) <= 0:
            raise ParameterError("gravity", float(stack.gravity), "> 0 to drop a stack from a height")
    return at_impact(stack, jnp.sqrt(2.0 * stack.gravity * h), gaps)


def invert_monotone(fn, target: Array, iterations: int = 40) -> Array:
    """Solve `fn(d) = target` elementwise for `d > 0`, `fn` increasing and positive (`target > 0`).

    Newton's method on `log fn(exp(u)) = log target`, which is linear for every power law (`k d^p`:
    exact after one step) and well conditioned for the others; a fixed number of iterations, so it is
    traceable, vmappable and differentiable (its derivative converges with it).
    """
    target = jnp.asarray(target, dtype=float)
    log_t = jnp.log(target)

    def residual(u):
        return jnp.log(fn(jnp.exp(u))) - log_t

    def body(_, u):
        r, dr = jax.jvp(residual, (u,), (jnp.ones_like(u),))
        step = jnp.clip(r / jnp.where(jnp.abs(dr) > 1e-300, dr, 1.0), -5.0, 5.0)
        return jnp.where(jnp.isfinite(step), u - step, u)

    u = jax.lax.fori_loop(0, iterations, body, jnp.zeros_like(target))
    return jnp.exp(u)


def resting(stack: Stack, height: ArrayLike = 0.0) -> State:
    """Initial state (c): a touching stack (zero gaps) in static equilibrium under gravity and the end
    force (a precompressed chain).

    Interface `j` carries the weight of the masses above it and the end force `F0` on the top mass,
    `W_j = g sum_{i > j} m_i + F0`, so its preload
    overlap solves `F^el_j(delta_j) = W_j` (Hertz: `delta_j = (W_j/k)^{2/3}`), found by `invert_monotone`
    for any law.

    - `height = 0`: the stack rests on the ground; the ground contact carries the whole weight
      (`x_1 = -delta_0`), every mass is at rest and the net force on every mass is zero.
    - `height > 0`: the preloaded stack is dropped from `height` with its preload kept (the usual
      idealisation of a stack held together by its guides): mass 1 just touches the ground
      (`x_1 = 0`) and every mass moves down at `sqrt(2 g h)`.

    Without the ground only `height = 0` makes sense and interface 0 carries nothing.
    """
    h = jnp.asarray(height, dtype=float)
    if not _is_concrete(h):
        h = _traced_rule(h, jnp.isfinite(h) & (h >= 0), "height", "finite and >= 0 (m)")
    elif not (np.isfinite(float(h)) and float(h) >= 0):
        raise ParameterError("height", float(h), "finite and >= 0 (m)")
    m, g = stack.masses, stack.gravity
    above = jnp.cumsum(m[::-1])[::-1]  # above[i] = sum_{k >= i} m_k
    weight = g * above + stack.end_force  # interface j (index j) carries the masses j+1..n and F0
    mask = (weight > 0) & stack.interface_mask()
    w_safe = jnp.where(mask, weight, 1.0)
    # masked entries solve d = 1 instead (finite values and gradients: the double-where trick)
    fn = lambda d: jnp.where(mask, stack.elastic_forces(d), d)  # noqa: E731
    delta = jnp.where(mask, invert_monotone(fn, w_safe), 0.0)
    on_ground = h <= 0
    x1 = jnp.where(on_ground, -delta[0], 0.0)
    x = x1 - jnp.concatenate([jnp.zeros(1), jnp.cumsum(delta[1:])])
    v_ff = jnp.sqrt(2.0 * g * jnp.maximum(h, 0.0))
    return State(x, jnp.broadcast_to(-v_ff, x.shape))


def precompressed(stack: Stack, force: ArrayLike, wall_stiffness: ArrayLike | None = None) -> tuple[Stack, State]:
    """A chain on the ground precompressed by a static force `F0` at its far end, at rest: `(stack, state)`.

    Without `wall_stiffness` the force is a dead load (`Stack.end_force = F0`). With it, the chain sits
    between the ground and a rigid far wall (`Stack.wall_stiffness`, N/m^1.5) placed where the wall's
    contact carries `F0` exactly: `x_w = x_n - (F0/k_w)^{2/3}` (the wall overlaps the top mass by the
    static Hertz overlap), and no end force acts. Either way every
    contact `j` carries `F0 + g sum_{i > j} m_i` (`resting`): the precompressed chain of Nesterenko
    (2001, "Dynamics of heterogeneous materials", Springer). Concrete (not traced) arguments; the
    returned state is at rest (give it velocities, e.g. a struck far bead, with `State`).

    **Raises:** `ParameterError` for a stack without the ground, or `F0` / `k_w` not finite and > 0.
    """
    f0 = float(np.asarray(force))
    if not (np.isfinite(f0) and f0 > 0):
        raise ParameterError("force", f0, "a finite number > 0 (N): the static precompression")
    if not stack.ground:
        raise ParameterError("stack.ground", False, "True (the ground is the wall at mass 1 that holds the chain)")
    laws = [stack.law_of(j) for j in stack.interfaces]
    loaded = Stack(stack.masses, laws, gravity=stack.gravity, ground=True, end_force=f0)
    rest = resting(loaded)
    if wall_stiffness is None:
        return loaded, rest
    kw = float(np.asarray(wall_stiffness))
    if not (np.isfinite(kw) and kw > 0):
        raise ParameterError("wall_stiffness", kw, "a finite number > 0 (N/m^1.5)")
    x_w = float(rest.positions[-1]) - (f0 / kw) ** (2.0 / 3.0)
    walled = Stack(stack.masses, laws, gravity=stack.gravity, ground=True, wall_stiffness=kw, wall_position=x_w)
    return walled, rest

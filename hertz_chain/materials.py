r"""Materials, contact geometry and Hertz stiffness (plain Python/NumPy, SI units).

* Effective modulus (Johnson 1985, *Contact Mechanics*, Eq. 4.22 / §4.2):
  $1/E^* = (1-\nu_1^2)/E_1 + (1-\nu_2^2)/E_2$; a rigid partner contributes 0.
* Effective radius: $1/R^* = 1/R_1 + 1/R_2$, a flat has $R = \infty$ (sphere–flat: $R^* = R_1$).
  Flat–flat contact is not Hertzian and is refused.
* Hertz stiffness $k = \tfrac43 E^*\sqrt{R^*}$ (N/m^1.5), so $F = k\delta^{3/2}$ (Johnson 1985, Eq. 4.23).
* Masses from geometry and density: sphere $\tfrac43\pi r^3\rho$, cylinder/disc $\pi r^2 h\rho$.
* Peak Hertz pressure $p_0 = (6 F E^{*2}/(\pi^3 R^{*2}))^{1/3}$ (Johnson 1985, Eq. 4.24); first yield
  under a sphere when $p_0 = 1.60\,Y$ (von Mises, $\nu = 0.3$; Johnson 1985, §6.2), the rule
  `YIELD_PRESSURE_FACTOR` that turns a yield strength $Y$ into a yield pressure $p_y = 1.6\,Y$.

The material table `hertz_chain/data/materials.csv` (shipped in the wheel; `data/materials.csv` at the
repository root links to it) has columns ``name,
youngs_modulus_Pa, poisson_ratio, density_kg_m3, typical_restitution, yield_strength_Pa, source``;
every row names its handbook/datasheet source. ``yield_strength_Pa`` (0.2 % offset, tension, in the
condition the row names) is empty where a tensile yield strength says nothing useful about contact
plasticity (cemented carbide, elastomers). The restitution column is **indicative** only (the coefficient of
restitution is not a material constant: it depends on speed, size and the partner).
"""

from __future__ import annotations

import csv
import functools
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import ParameterError, check_number, check_positive

__all__ = [
    "YIELD_PRESSURE_FACTOR",
    "hertz_peak_pressure",
    "YieldLimit",
    "Material",
    "MATERIALS_CSV",
    "material",
    "material_names",
    "load_materials",
    "effective_modulus",
    "effective_radius",
    "effective_mass",
    "hertz_stiffness",
    "contact_stiffness",
    "sphere_mass",
    "cylinder_mass",
    "disc_mass",
]

MATERIALS_CSV = Path(__file__).resolve().parent / "data" / "materials.csv"

#: `p_y = YIELD_PRESSURE_FACTOR * Y`: the peak Hertz pressure at first yield under a sphere, 1.60 Y for a
#: von Mises (or Tresca) material with nu = 0.3 (Johnson 1985, *Contact Mechanics*, §6.2; the exact on-axis value is
#: 1.613 at nu = 0.3 and 1.55-1.67 over nu = 0.25-0.35, so the fixed 1.6 is a stated rule, within ~4 % for metals).
YIELD_PRESSURE_FACTOR = 1.6


_number = check_number
_positive = check_positive


def _poisson(value, name: str = "poisson_ratio") -> float:
    v = _number(value, name)
    # Isotropic elastic stability: -1 < nu <= 1/2 (1/2: incompressible limit, e.g. rubber).
    if not (-1.0 < v <= 0.5):
        raise ParameterError(name, value, "-1 < nu <= 0.5 for an isotropic elastic solid")
    return v


@dataclass(frozen=True)
class Material:
    """An isotropic elastic material (SI units).

    ``typical_restitution`` is indicative only (``None`` if unknown); ``yield_strength`` (Pa, ``None``
    if unknown or not meaningful) gives `yield_pressure`; ``source`` cites the data.
    """

    name: str
    youngs_modulus: float
    poisson_ratio: float
    density: float | None = None
    typical_restitution: float | None = None
    source: str = ""
    yield_strength: float | None = None

    def __post_init__(self):
        object.__setattr__(self, "youngs_modulus", _positive(self.youngs_modulus, "youngs_modulus"))
        object.__setattr__(self, "poisson_ratio", _poisson(self.poisson_ratio))
        if self.density is not None:
            object.__setattr__(self, "density", _positive(self.density, "density"))
        if self.typical_restitution is not None:
            e = _number(self.typical_restitution, "typical_restitution")
            if not (0.0 < e <= 1.0):
                raise ParameterError("typical_restitution", e, "in (0, 1]")
            object.__setattr__(self, "typical_restitution", e)
        if self.yield_strength is not None:
            object.__setattr__(self, "yield_strength", _positive(self.yield_strength, "yield_strength"))

    @property
    def yield_pressure(self) -> float | None:
        """$p_y = 1.6 Y$ (Pa; `YIELD_PRESSURE_FACTOR`): the peak Hertz pressure at which a sphere contact on
        this material first yields; ``None`` without a yield strength."""
        return None if self.yield_strength is None else YIELD_PRESSURE_FACTOR * self.yield_strength

    @property
    def plane_strain_compliance(self) -> float:
        """$(1 - \\nu^2)/E$ (1/Pa), this material's share of $1/E^*$."""
        return (1.0 - self.poisson_ratio**2) / self.youngs_modulus


def _key(name: str) -> str:
    return " ".join(str(name).strip().lower().replace("_", "-").split())


@functools.lru_cache(maxsize=4)
def _load(path: str) -> dict[str, Material]:
    table: dict[str, Material] = {}
    with open(path, newline="", encoding="utf-8") as fh:
        for row in csv.DictReader(fh):
            e = row.get("typical_restitution", "").strip()
            rho = row.get("density_kg_m3", "").strip()
            sy = (row.get("yield_strength_Pa") or "").strip()
            mat = Material(
                name=row["name"].strip(),
                youngs_modulus=float(row["youngs_modulus_Pa"]),
                poisson_ratio=float(row["poisson_ratio"]),
                density=float(rho) if rho else None,
                typical_restitution=float(e) if e else None,
                source=row.get("source", "").strip(),
                yield_strength=float(sy) if sy else None,
            )
            table[_key(mat.name)] = mat
    return table


def load_materials(path: str | Path | None = None) -> dict[str, Material]:
    """The material table as ``{name: Material}`` (default: `MATERIALS_CSV`)."""
    table = _load(str(MATERIALS_CSV if path is None else Path(path)))
    return {m.name: m for m in table.values()}


def material_names() -> tuple[str, ...]:
    """Names in the package's material table."""
    return tuple(m.name for m in _load(str(MATERIALS_CSV)).values())


def material(name: str | Material) -> Material:
    """Look up a material by name (case-insensitive, ``_`` = ``-``); a `Material` passes through."""
    if isinstance(name, Material):
        return name
    table = _load(str(MATERIALS_CSV))
    try:
        return table[_key(name)]
    except KeyError:
        raise ParameterError("material", name, f"one of {list(material_names())}") from None


def effective_modulus(mat1: str | Material | None, mat2: str | Material | None = None) -> float:
    r"""$E^* = [(1-\nu_1^2)/E_1 + (1-\nu_2^2)/E_2]^{-1}$ (Pa); ``None`` is a rigid body."""
    compliance = sum(material(m).plane_strain_compliance for m in (mat1, mat2) if m is not None)
    if compliance == 0.0:
        raise ParameterError("material", (mat1, mat2), "at least one deformable body")
    return 1.0 / compliance


def effective_radius(R1: float, R2: float | None = None) -> float:
    r"""$R^* = (1/R_1 + 1/R_2)^{-1}$ (m); ``R2 = None`` or ``inf`` is a flat (sphere–flat: $R_1$)."""
    r1 = _positive(R1, "R1", allow_inf=True)
    r2 = math.inf if R2 is None else _positive(R2, "R2", allow_inf=True)
    inv = (0.0 if math.isinf(r1) else 1.0 / r1) + (0.0 if math.isinf(r2) else 1.0 / r2)
    if inv == 0.0:
        raise ParameterError("R1", R1, "flat-on-flat contact is not Hertzian: give a finite radius")
    return 1.0 / inv


def effective_mass(m1: float, m2: float | None = None) -> float:
    r"""$m^* = m_1 m_2/(m_1 + m_2)$ (kg); ``m2 = None`` or ``inf`` is the ground ($m^* = m_1$)."""
    a = _positive(m1, "m1", allow_inf=True)
    b = math.inf if m2 is None else _positive(m2, "m2", allow_inf=True)
    if math.isinf(a) and math.isinf(b):
        raise ParameterError("m1", m1, "at least one finite mass")
    if math.isinf(a):
        return b
    if math.isinf(b):
        return a
    return a * b / (a + b)


def hertz_stiffness(E_star: float, R_star: float) -> float:
    r"""$k = \tfrac43 E^*\sqrt{R^*}$ (N/m^1.5; Johnson 1985, Eq. 4.23)."""
    return 4.0 / 3.0 * _positive(E_star, "E_star") * math.sqrt(_positive(R_star, "R_star"))


def contact_stiffness(
    mat1: str | Material | None,
    mat2: str | Material | None,
    R1: float,
    R2: float | None = None,
) -> float:
    """Hertz stiffness of two bodies of materials ``mat1``/``mat2`` (``None``: rigid) and radii of
    curvature ``R1``/``R2`` at the contact (``None`` or ``inf``: flat), N/m^1.5."""
    return hertz_stiffness(effective_modulus(mat1, mat2), effective_radius(R1, R2))


def hertz_peak_pressure(force, E_star: float, R_star: float):
    r"""Peak (central) Hertz pressure $p_0 = (6 F E^{*2}/(\pi^3 R^{*2}))^{1/3}$ (Pa) of a sphere contact
    carrying ``force`` (N; a number or array), Johnson 1985, Eq. 4.24."""
    f = np.maximum(np.asarray(force, dtype=float), 0.0)
    return np.cbrt(6.0 * f * E_star**2 / (math.pi**3 * R_star**2))


@dataclass(frozen=True)
class YieldLimit:
    """Where an interface first yields: its effective modulus `E*` (Pa) and radius `R*` (m) from the
    materials and radii, and the yield pressure `p_y = 1.6 Y` (Pa) of the softer body with a yield
    strength (`material` names it; `materials.YIELD_PRESSURE_FACTOR`), with that body's yield strength `Y`
    (Pa) and Poisson ratio."""

    interface: int
    modulus: float
    radius: float
    yield_pressure: float
    material: str
    yield_strength: float = float("nan")
    poisson_ratio: float = 0.3

    def peak_pressure(self, force):
        """`hertz_peak_pressure` of this interface at `force` (N)."""
        return hertz_peak_pressure(force, self.modulus, self.radius)


def _density(density: float | str | Material) -> float:
    if isinstance(density, (str, Material)):
        mat = material(density)
        if mat.density is None:
            raise ParameterError("density", mat.name, "material has no density in the table")
        return mat.density
    return _positive(density, "density")


def sphere_mass(radius: float, density: float | str | Material) -> float:
    r"""$\tfrac43\pi r^3\rho$ (kg); ``density`` in kg/m³ or a material (name)."""
    return 4.0 / 3.0 * math.pi * _positive(radius, "radius") ** 3 * _density(density)


def cylinder_mass(radius: float, height: float, density: float | str | Material) -> float:
    r"""$\pi r^2 h\rho$ (kg) of a solid cylinder (or disc); ``density`` in kg/m³ or a material."""
    return math.pi * _positive(radius, "radius") ** 2 * _positive(height, "height") * _density(density)


def disc_mass(radius: float, thickness: float, density: float | str | Material) -> float:
    """Mass of a disc of ``thickness`` (same as `cylinder_mass`)."""
    return cylinder_mass(radius, thickness, density)

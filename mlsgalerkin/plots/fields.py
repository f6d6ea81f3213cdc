r"""The fields a picture can be coloured by: label, SI unit, colour map, categorical or not.

One table, :data:`FIELDS`, says how each point-data array of the fluid's VTU frames (written by
``FluidState.frame()``) is drawn:

=================  ============================  ======  ===========  ==========================
name               colour-bar label              unit    colour map   kind
=================  ============================  ======  ===========  ==========================
``pressure``       pressure                      Pa      viridis      continuous
``density``        density                       kg/m³   cividis      continuous
``density_ratio``  density ratio ρ/ρ0            –       coolwarm     continuous, centred on 1
``speed``          speed \|v\|                   m/s     plasma       continuous
``velocity``       velocity magnitude \|v\|      m/s     plasma       continuous (vector: norm)
``velocity_x``     horizontal velocity v_x       m/s     coolwarm     continuous, centred on 0
``velocity_y``     vertical velocity v_y         m/s     coolwarm     continuous, centred on 0
``phase``          phase                                 tab10        categorical (phase index)
``mls_order``      MLS order used                        tab10        categorical (0, 1, 2)
``free_surface``   free-surface flag                     tab10        categorical (0/1)
``is_wall``        wall flag                             tab10        categorical (0/1)
=================  ============================  ======  ===========  ==========================

``free_surface`` is written only when the scene lists the ``FreeSurfaceDetection`` effect.
A vector array ``NAME`` (shape ``(n, 3)`` in a VTU file) is drawn as its magnitude, and
``NAME_x``, ``NAME_y``, ``NAME_z`` as its components. A field of one's own (an effect's
``extra`` array) is added with :func:`register_field`; an array of a VTU file that is not in
the table can still be drawn (its colour bar then names it without a unit).

>>> FIELDS["pressure"].axis_label
'pressure (Pa)'
>>> values, style = resolve_field({"velocity": [[3.0, 4.0, 0.0]]}, "velocity_x")
>>> float(values[0]), style.axis_label
(3.0, 'horizontal velocity v_x (m/s)')
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "FIELDS",
    "FieldStyle",
    "available_fields",
    "field_name_problem",
    "known_fields",
    "register_field",
    "resolve_field",
]

_COMPONENTS = ("x", "y", "z")


@dataclass(frozen=True)
class FieldStyle:
    """How one field is drawn.

    Parameters
    ----------
    name : str
        Point-data array name (as in the VTU files), or ``VECTOR_x`` for a component.
    label : str
        Words for the colour bar or legend title, e.g. ``"pressure"``.
    unit : str
        SI unit, e.g. ``"Pa"``; ``"–"`` for a dimensionless number; ``""`` for categories.
    cmap : str
        Matplotlib colour-map name.
    categorical : bool
        Integer categories drawn with distinct colours and a legend instead of a colour bar.
    categories : mapping of int to str
        Legend text of known category values; others read ``"{label} {value}"``.
    center : float, optional
        Centre the colour range on this value (a diverging colour map: zero velocity, ρ/ρ0 = 1).
    description : str
        One sentence for a caption: what the field is.
    """

    name: str
    label: str
    unit: str
    cmap: str = "viridis"
    categorical: bool = False
    categories: Mapping[int, str] = field(default_factory=dict, hash=False)
    center: float | None = None
    description: str = ""

    @property
    def axis_label(self) -> str:
        """The colour-bar label: ``"label (unit)"``, or the label alone without a unit."""
        return f"{self.label} ({self.unit})" if self.unit else self.label

    def category_label(self, value: int) -> str:
        """Legend text of the category ``value``."""
        return self.categories.get(int(value), f"{self.label} {int(value)}")


FIELDS: dict[str, FieldStyle] = {
    s.name: s
    for s in (
        FieldStyle("pressure", "pressure", "Pa", "viridis",
                   description="the pressure p of the Tait equation of state (gauge, Pa)"),
        FieldStyle("density", "density", "kg/m³", "cividis",
                   description="the particle density ρ (kg/m³)"),
        FieldStyle("density_ratio", "density ratio ρ/ρ0", "–", "coolwarm", center=1.0,
                   description="the density relative to the phase's reference density, ρ/ρ0"),
        FieldStyle("speed", "speed |v|", "m/s", "plasma",
                   description="the particle speed |v| (m/s)"),
        FieldStyle("velocity", "velocity magnitude |v|", "m/s", "plasma",
                   description="the magnitude of the particle velocity (m/s)"),
        FieldStyle("velocity_x", "horizontal velocity v_x", "m/s", "coolwarm", center=0.0,
                   description="the horizontal velocity v_x (m/s; red to the right, blue to the left)"),
        FieldStyle("velocity_y", "vertical velocity v_y", "m/s", "coolwarm", center=0.0,
                   description="the vertical velocity v_y (m/s; red upwards, blue downwards)"),
        FieldStyle("velocity_z", "velocity v_z", "m/s", "coolwarm", center=0.0,
                   description="the velocity component v_z (m/s)"),
        FieldStyle("phase", "phase", "", "tab10", categorical=True,
                   description="the phase index of each fluid particle (0 is the scene's first phase)"),
        FieldStyle("mls_order", "MLS order used", "", "tab10", categorical=True,
                   categories={0: "order 0 (Shepard)", 1: "order 1 (linear)", 2: "order 2 (quadratic)"},
                   description="the polynomial order of the MLS shape functions at each particle "
                               "(lower than requested where the neighbourhood was too sparse)"),
        FieldStyle("free_surface", "free-surface flag", "", "tab10", categorical=True,
                   categories={0: "interior", 1: "free surface"},
                   description="the particles detected on the free surface"),
        FieldStyle("is_wall", "wall flag", "", "tab10", categorical=True,
                   categories={0: "fluid", 1: "wall"},
                   description="fluid (0) or wall (1) particle"),
    )
}

#: Fields written only when an effect provides them: field -> what to add to the scene.
_CONDITIONAL = {"free_surface": "with the FreeSurfaceDetection effect"}


def register_field(style: FieldStyle) -> None:
    """Add (or replace) the style of a field, e.g. an ``extra`` array of an effect of one's own,
    so ``Output(color_by=style.name)`` accepts it and its pictures name its unit."""
    if not isinstance(style, FieldStyle):
        raise TypeError(f"register_field expects a FieldStyle, got {type(style).__name__}")
    FIELDS[style.name] = style


def known_fields() -> list[str]:
    """The names of the table, sorted."""
    return sorted(FIELDS)


def field_name_problem(name: object) -> str | None:
    """``None`` if ``name`` is a field of the table, else a message listing the known fields
    (used to check ``Output.color_by`` before a run starts)."""
    if isinstance(name, str) and name in FIELDS:
        return None
    listed = ", ".join(f"{n} ({_CONDITIONAL[n]})" if n in _CONDITIONAL else n for n in known_fields())
    return (f"{name!r} is not a field of the fluid frames; choose one of: {listed} "
            "(or add a field of your own with mlsgalerkin.plots.fields.register_field)")


def available_fields(data: Mapping[str, np.ndarray], dim: int = 2) -> list[str]:
    """The names :func:`resolve_field` accepts for the point data ``data``: each array, and
    ``NAME_x``, ``NAME_y`` (``NAME_z`` with ``dim = 3``) of each vector array; sorted."""
    out = []
    for key, value in data.items():
        out.append(key)
        if np.ndim(value) == 2:
            out.extend(f"{key}_{c}" for c in _COMPONENTS[: min(dim, np.shape(value)[1])])
    return sorted(out)


def resolve_field(data: Mapping[str, np.ndarray], name: str, dim: int = 2) -> tuple[np.ndarray, FieldStyle]:
    """The values ``(n,)`` (float64) and the style of field ``name`` in the point data ``data``.

    A vector array gives its Euclidean norm; ``NAME_x``/``_y``/``_z`` a component. A field missing
    from ``data`` raises :class:`ValueError` listing the available ones.
    """
    if name in data:
        values = np.asarray(data[name])
        if values.ndim == 2:
            values = np.linalg.norm(np.asarray(values, dtype=np.float64), axis=1)
    else:
        base, _, comp = name.rpartition("_")
        vector = np.asarray(data[base]) if base in data else None
        if vector is None or vector.ndim != 2 or comp not in _COMPONENTS or \
                _COMPONENTS.index(comp) >= vector.shape[1]:
            raise ValueError(f"the frames have no field {name!r}; available: "
                             f"{', '.join(available_fields(data, dim))}")
        values = vector[:, _COMPONENTS.index(comp)]
    if values.ndim != 1:
        raise ValueError(f"field {name!r} has shape {values.shape}; only scalars and vectors can be drawn")
    style = FIELDS.get(name) or FieldStyle(name, name.replace("_", " "), "", "viridis",
                                           categorical=np.issubdtype(values.dtype, np.integer))
    return np.asarray(values, dtype=np.float64), style

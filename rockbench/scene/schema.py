"""The scene format, field by field: the one table that the scene classes validate against and
that ``docs/scenes.md`` is generated from (:func:`markdown`; a test checks that the committed
page equals its output).

Each :class:`Field` says the TOML table it belongs to, its unit, its valid range (a key of
:data:`rockbench.limits.LIMITS`, so that the range, its reason and its environment override are
said once, or an explicit range for the few that are not adjustable), its default and its
meaning. A field without a default is **required**: a scene file that leaves it out is refused
with one line naming it. Defaults are physical (the density of concrete, a uniform beam), never
the paper's choices: those live in the paper's scene files (``rockbench/scenarios/``) and in
``preset = "paper"``.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..limits import LIMITS

__all__ = ["Field", "FIELDS", "fields_of", "required", "markdown"]


@dataclass(frozen=True)
class Field:
    """One key of a scene file.

    table : "scene" (top level), "block", "frame", "devices" or "contact";
    name : the key; unit : SI unit ("-" dimensionless, "" for text);
    limit : key of :data:`rockbench.limits.LIMITS` giving the range, or None (``valid`` says it);
    valid : the range in words when ``limit`` is None (or extra conditions besides it);
    default : the default as text, None for a required field;
    meaning : one line.
    """

    table: str
    name: str
    unit: str
    limit: str | None
    valid: str
    default: str | None
    meaning: str

    @property
    def is_required(self) -> bool:
        return self.default is None

    def range_text(self) -> str:
        """The valid range as text, e.g. ``"[0.001, 1000] m"``."""
        if self.limit is None:
            return self.valid
        lim = LIMITS[self.limit]
        text = lim.describe(lim.lo, lim.hi).replace("in ", "", 1)
        return f"{text}; {self.valid}" if self.valid else text


_UNIFORM_RHO = "sqrt((beam_width^2 + beam_height^2) / 12), a uniform rectangular beam"
_SOLID_BEAM = "density x beam_width x beam_height x depth, a solid beam of the columns' material"

#: Every field of a scene file, by table, in the order the docs list them.
FIELDS: tuple[Field, ...] = (
    # --- top level -----------------------------------------------------------------------------
    Field("scene", "kind", "", None, '"scene"', '"scene"',
          "what the file is (the case catalogue cases.toml says another kind)"),
    Field("scene", "name", "", None, "text", '"custom"',
          "the scene's name, used in reports and store keys"),
    Field("scene", "version", "", None, "an integer", "none",
          "version of the scene's data, for your own bookkeeping"),
    Field("scene", "description", "", None, "text", '""', "one line about the structure"),
    Field("scene", "preset", "", None, '"paper"', "none",
          'take every structure and device field left out from the paper\'s asymmetric frame '
          '(rockbench/scenarios/paper-asymmetric.toml) and its hybrid devices '
          '(paper-asymmetric-hybrid.toml); frames only'),
    Field("scene", "fall_angle", "rad", None, "(0, pi]",
          "0.98 x min(pi/2, the mechanism's geometric limit), per direction",
          "the rotation abs(phi) at which a run reports overturned (and may stop)"),
    # --- block -----------------------------------------------------------------------------------
    Field("block", "width", "m", "length", "width / height <= sqrt(2) (eta >= 0)", None,
          "base width 2b"),
    Field("block", "height", "m", "length", "", None, "height 2H"),
    Field("block", "depth", "m", "length", "", "1.0",
          "out-of-plane depth (masses, hence device effects, scale with it)"),
    Field("block", "density", "kg/m^3", "density", "", "2500.0 (normal-weight concrete)",
          "mass density"),
    # --- frame -----------------------------------------------------------------------------------
    Field("frame", "column_width", "m", "length", "< span; eta >= 0 in both directions", None,
          "width 2b of both columns (the model has one width for both)"),
    Field("frame", "column_height_left", "m", "length", "", None,
          "height 2H of the left, taller column AB: it defines alpha and p"),
    Field("frame", "column_height_right", "m", "length", "<= column_height_left", None,
          "height 2H1 of the right column CD, on a foundation step 2(H - H1) high"),
    Field("frame", "span", "m", "length", "> column_width", None,
          "centre-to-centre distance L of the columns"),
    Field("frame", "beam_width", "m", "length", ">= span + column_width", None,
          "length of the cap beam (it covers both column tops; its centre of mass is at "
          "mid-span)"),
    Field("frame", "beam_height", "m", "length", "", None, "depth 2h of the cap beam"),
    Field("frame", "beam_gyration_radius", "m", "length", "", _UNIFORM_RHO,
          "polar radius of gyration rho of the beam about its centre of mass"),
    Field("frame", "beam_mass", "kg", None,
          "> 0, with beam_mass / left column mass in the mass_ratio range", _SOLID_BEAM,
          "mass m_BC of the cap beam (give it, or mass_ratio, or neither)"),
    Field("frame", "mass_ratio", "-", "mass_ratio",
          "if beam_mass is given too, they must agree (to 1e-9)", "none (see beam_mass)",
          "beam mass / left column mass m_BC / m_AB, an alternative to beam_mass"),
    Field("frame", "depth", "m", "length", "", "1.0",
          "out-of-plane depth of the columns (masses scale with it)"),
    Field("frame", "density", "kg/m^3", "density", "", "2500.0 (normal-weight concrete)",
          "mass density of the columns (and of the default beam)"),
    # --- devices ---------------------------------------------------------------------------------
    Field("devices", "tendon_stiffness", "N/m", "stiffness", "0 = no tendons", None,
          "axial stiffness k = EA/l of each of the two unbonded, unstressed central tendons"),
    Field("devices", "tendon_length", "m", "length", "", None,
          "free length l of each tendon (strain = elongation / l)"),
    Field("devices", "fracture_strain", "-", None,
          '[0.0001, 1) (no tendon breaks below 0.01 %), or "none" (never fractures)',
          None, "tendon strain eps_f at which every tendon and damper fails at once (brittle)"),
    Field("devices", "damping", "N s/m", "damping", "0 = no dampers", None,
          "constant C of each of the two linear viscous dampers at the column heels"),
    # --- contact ---------------------------------------------------------------------------------
    Field("contact", "friction", "-", None, "(0, 10]",
          "none: each engine's own (docs/engines/README.md), pivots that do not slide",
          "Coulomb coefficient mu (static = kinetic) of the base contacts: a block's or the "
          "columns' base corners on the foundation"),
    Field("contact", "beam_friction", "-", None, "(0, 10]; frames only; needs friction",
          "friction", "Coulomb coefficient of the beam on its columns' top corners"),
)

_TABLES = ("scene", "block", "frame", "devices", "contact")


def fields_of(table: str) -> tuple[Field, ...]:
    """The fields of ``table`` ("scene", "block", "frame", "devices" or "contact"), in
    order."""
    if table not in _TABLES:
        raise KeyError(table)
    return tuple(f for f in FIELDS if f.table == table)


def required(table: str) -> tuple[str, ...]:
    """Names of the required fields of ``table``."""
    return tuple(f.name for f in fields_of(table) if f.is_required)


def _table(table: str) -> str:
    rows = ["| field | unit | valid range | default | meaning |", "|---|---|---|---|---|"]
    for f in fields_of(table):
        default = "**required**" if f.is_required else f.default
        unit = f.unit or " "
        rows.append(f"| `{f.name}` | {unit} | {f.range_text()} | {default} | {f.meaning} |")
    return "\n".join(rows)


def _limits_table() -> str:
    keys = sorted({f.limit for f in FIELDS if f.limit}, key=list(LIMITS).index)
    rows = ["| range | default | environment variable | why |", "|---|---|---|---|"]
    for k in keys:
        lim = LIMITS[k]
        rows.append(f"| `{k}` | {lim.describe(lim.lo, lim.hi)} | `{lim.env}` | {lim.why} |")
    return "\n".join(rows)


_HEAD = """# Scenes: the structure you give rockbench, field by field

<!-- generated from rockbench/scene/schema.py by
`python -c "from rockbench.scene.schema import markdown; print(markdown(), end='')" > docs/scenes.md`;
tests/scene/test_scene_format.py checks that this page is its output. Edit the schema, not
this page. -->

A scene is a structure (a rigid block, or the rocking frame: two rigid columns capped by a rigid
beam, joined by contacts only), its optional devices (tendons and dampers, frames only) and a
few options. It is data: a TOML file, or a `rockbench.Scene` in Python. Every command takes a
built-in scene name (`rockbench scenes` lists them) or a path to a `.toml` file; in Python
`rb.load_scene` turns either into a `Scene`, and every function that takes a scene name or
file (`advise`, `tradeoff`, `run_map`, ...) takes a `Scene` too.

```toml
name = "bridge-bent"
description = "two-column bridge bent: 1.2 x 6 m columns, L = 7 m, 10 x 1.5 m cap beam"
[structure]
type = "frame"
column_width = 1.2
column_height_left = 6.0
column_height_right = 6.0
span = 7.0
beam_width = 10.0
beam_height = 1.5
beam_mass = 300000.0           # cap beam and its share of the deck [kg]
depth = 1.2
[devices]                      # optional; all four fields, or no [devices] table
tendon_stiffness = 30e6
tendon_length = 8.0
fracture_strain = 0.02         # or "none"
damping = 5e6
[contact]                      # optional; left out: no sliding (each engine's own friction)
friction = 0.6
```

Units are SI (m, kg, s, N, rad). **A field without a default is required**: a file that leaves
one out is refused with one line naming it (`rockbench: error: ...`, exit status 2). Defaults
are physical (the density of concrete, a uniform beam); **the paper's values are never filled
in silently**: they are in the paper's scene files (`rockbench/scenarios/paper-*.toml`), or
taken on purpose with `preset = "paper"`. Every range below is checked when the scene is made,
before any arithmetic; the ranges marked with a limit can be widened with its environment
variable (see [errors.md](errors.md)).

Python: `rb.load_scene(name | path | Scene, overrides)`, `rb.Scene(rb.Frame(...),
rb.Devices(...))`, `scene.to_toml()`, `rb.save_scene(scene, path)` (a saved scene loads back
equal). The command line changes any field with `--set KEY=VALUE` (`--set span=9`,
`--set devices.fracture_strain=none`, `--set devices=none` removes the devices,
`--set contact.friction=0.3`, `--set contact=none` removes the friction; setting `mass_ratio`
replaces a `beam_mass` and the other way round).
"""

_CONTACT = """

**No friction given** (no `[contact]` table) is the rocking model's assumption: pivots that do not
slide. Each engine then uses its own default coefficient (its setting `friction`, listed in
[engines/README.md](engines/README.md)), chosen high enough that the structures it is checked
on do not slide, and a run whose contacts slide more than the engine's `max_sliding` setting is
reported `diverged`. **A friction given** is
physics: every engine gives every base contact pair exactly `friction` (and the beam on the
column tops `beam_friction`, default `friction`), whatever its own rule of combining two
bodies' coefficients; sliding is then modelled, not an error (a run is not marked for it, and
its `max_sliding` reports the largest slip, [metrics.md](metrics.md)), and an engine setting
`friction=...` on top of it is refused. The analytic rocking model never slides: where the
scene's friction is below what its pivots need, `rockbench.validity` puts the case outside the
model. Newmark's sliding block (`rockbench.analytic.sliding`) is the exact reference for a
structure that slides without rocking ([sliding.md](sliding.md))."""


_MODEL = """## What the model supports (and what it does not)

The analytic model (Dimitrakopoulos & Giouvanidis 2015) and every engine build the same
structure; these are its limits, checked or built in:

* **Rigid bodies on a rigid foundation, no sliding, no bouncing.** Pivots stick; an impact is
  perfectly plastic at the new pivots (the paper's impulse equations, Eqs. 22-28). Its
  coefficient of restitution eta follows from the geometry and masses: a structure for which it
  is negative cannot rock (it stops at the first impact) and is refused, naming the widest
  column it accepts. For a block eta = 1 - 1.5 sin^2(alpha) >= 0 means width / height <=
  sqrt(2) (alpha <= 54.7 deg); for a frame the limit depends on the beam and is computed from
  the frame's own eta. (For an asymmetric frame eta may exceed 1: it is the ratio of the left
  column's angular velocities in two mechanisms of different inertia; the kinetic energy still
  drops at every impact, eta^2 I_after <= I_before.)
* **The frame's three-block mechanism must hold up to |phi| = alpha** in both directions: a squat
  frame with very unequal columns, whose beam would bear on a column's other top corner, is
  refused.
* **Both columns have the same width** (`column_width`) and density; they may differ in height,
  the left column being the taller one (mirror your structure if yours is the other way). The
  shorter column stands on a foundation step so that both tops are level.
* **The cap beam is centred**: its centre of mass is at mid-span (x = L/2) and mid-depth; it
  rests on both column tops, so `beam_width >= span + column_width`. An overhang to one side
  is not modelled.
* **Devices on frames only**, one of each per column: an unbonded central tendon **without
  pretension** (slack at rest, elastic until brittle fracture at `fracture_strain`; both
  tendons have the same stiffness and length) and a linear viscous damper at the uplifting
  heel. When either tendon reaches `fracture_strain`, every tendon and damper is removed (the
  paper's simultaneous brittle failure). A block takes no devices.
* **Planar** motion; `depth` only scales the masses (and so the devices' effect against them).

The paper's frame, written out, is `rockbench/scenarios/paper-asymmetric.toml`; its hybrid
version `paper-asymmetric-hybrid.toml`. Worked examples of structures the paper does not treat
are in [docs/examples/](examples/) (a two-column bridge bent with tendons and dampers, and a
museum pedestal).
"""


def markdown() -> str:
    """The text of ``docs/scenes.md``."""
    parts = [_HEAD,
             "## Top level\n\n" + _table("scene"),
             "## `[structure]` with `type = \"block\"`: a free-standing rigid block\n\n"
             + _table("block"),
             "## `[structure]` with `type = \"frame\"`: the rocking frame\n\n" + _table("frame")
             + "\n\nThe beam's mass is `beam_mass`, or `mass_ratio` x the left column's mass, "
               "or (neither given) a solid beam of the columns' density. Masses: a column is "
               "density x column_width x its height x depth; inertias about the centre of mass "
               "are m R^2 / 3 for a column (R its half diagonal) and m_BC rho^2 for the beam.",
             "## `[devices]`: tendons and dampers (frames only)\n\n" + _table("devices")
             + "\n\nA `[devices]` table has all four fields or is left out (a free-standing "
               "frame). Tendons only: `damping = 0`; dampers only: `tendon_stiffness = 0` (a "
               "`tendon_length` is still required, and unused).",
             "## `[contact]`: friction (optional)\n\n" + _table("contact") + _CONTACT,
             "## The ranges\n\n" + _limits_table(),
             _MODEL]
    return "\n\n".join(p.strip("\n") for p in parts) + "\n"


if __name__ == "__main__":  # pragma: no cover - exercised by the docs test through markdown()
    print(markdown(), end="")

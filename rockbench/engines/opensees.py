"""OpenSees (OpenSeesPy) backend: the rocking structure as a structural engineer builds it.

Model (one 2-D model, ``ndm 2 / ndf 3``, built from the scene's body specs)
--------------------------------------------------------------------------
* **Bodies.** One node per body at its centre of mass carrying the scene's mass and in-plane
  inertia (m, m, I). Every point of a body that touches something (contact points, tendon
  anchors, damper corners) is a massless node tied to that centre-of-mass node by a very stiff
  *corotational* ``elasticBeamColumn`` (axial EA/L and tip bending 3EI/L^3 both
  ``member_ratio`` x the toe stiffness): a rigid member that stays exact at large rotations
  (OpenSees' ``rigidLink`` is a linear constraint: its corners drift by r (1 - cos theta)).
* **Contacts.** Every interface the mechanism uses - each column base (block base) on the
  foundation (the right column on the step of the asymmetric frame) and each column top against
  the beam soffit - carries ``springs`` node-to-node ``zeroLengthContact2D`` elements spread
  evenly over its width, corners included, normal (0, 1): compression-only penalty contact of
  stiffness ``toe_stiffness / springs`` each, with Coulomb friction (the base friction on the
  foundation, the beam friction under the beam:
  :attr:`~rockbench.engines.base.EngineBackend.friction_pairs`, the scene's or else
  ``friction``) and a tangential penalty ``tangential_ratio`` times the normal one. A lifted heel carries no
  force, normal or tangential (a horizontal spring that stays active while the heel is lifted
  drags it: eta +3.8 .. +5.0 %, measured). The lower node of each pair sits
  :data:`SEAT` = 1e-10 m above the upper one, so that every contact is closed from the first
  Newton iteration (at exactly zero gap Newton cycles between contact states and the first
  step of the asymmetric frame never converges at toe stiffness >= 3e12 N/m).
* **Impacts.** No contact damping by default: the impact is made plastic by the integrator.
  Newmark with gamma = 1.5, beta = 1 has spectral radius 0 at high frequency and annihilates
  the contact's vibration within a step (sqrt(k/m) dt ~ 11 for the beam on its columns), which
  is Housner's perfectly plastic, instantaneous impact; its first-order damping of the rocking
  itself costs 0.2-0.3 % of eta at dt = 1e-3 s (halves with dt). Rayleigh damping of the toes
  ("stiffness": proportional to the committed stiffness, through a parallel compression-only
  dashpot) or of the bodies ("mass") is available for comparison: both take energy from
  every impact or every excursion (``docs/engines/opensees.md``).
* **Ground motion.** The shared loop's per-step gravity ``gravity_x = -u_g''(t + dt/2)`` as a
  horizontal nodal load m gravity_x at each centre-of-mass node (the relative-motion
  formulation of a uniform excitation: only these nodes have mass), and with a vertical ground
  motion the vertical load m (gravity_y + g) = -m u_v'', in a ``Plain`` load pattern
  re-created every step; gravity is a constant pattern. The foundation nodes are fixed: the
  model is the foundation's frame, so the compression-only contacts open and close as the
  ground's vertical acceleration changes their load.
* **Devices** (``devices="native"``, the default). Tendon j: a ``corotTruss`` from its
  foundation anchor F (rest position of the column's base centre) to its beam anchor T (rest
  position of the column's top centre, a node of the beam), tension-only elastic material
  with EA = k L_j, L_j = |T - F| = the column height, so that its axial stiffness is the
  scene's k = EA / l. The straight truss elongates by |T - F| - L_j, which agrees with the
  scene model's base + top opening to first order and is shorter at second order (the
  measured difference is in the docs). Fracture (decided by the loop from the shared
  elongation) removes the truss elements. Dampers (``damper``): "distributed" (default) and
  "couple" are the shared :class:`~rockbench.engines.devices.DeviceGeometry` damper forces,
  applied per step as nodal loads at the centre-of-mass nodes; "heel" is a ``Viscous``
  ``zeroLength`` dashpot (vertical) between each base corner of a column and a fixed node at
  its rest position, the literal device. ``devices="forces"`` applies every device through
  the loop's shared point forces instead.
* **Analysis.** ``Transient``, Newton, ``NormDispIncr`` test (``tolerance`` m, ``iterations``),
  ``BandGeneral``, RCM numbering, Newmark or HHT with a fixed step ``dt``. An increment that
  does not converge is retried as two half steps, recursively, at most ``halvings`` times
  (each converged sub-step is kept); beyond that ``_step`` raises and the loop reports the run
  ``diverged`` with the time and the step that failed.

OpenSeesPy holds **one global model per process**: every build starts with ``wipe()`` and
every run ends with ``wipe()``, so consecutive runs in one process are independent (tested:
identical histories); two runs must not be interleaved (threads). OpenSees' own messages
(warnings of failed iterations) go to ``logFile('/dev/null', '-noEcho')``; the library's
"Process 0 Terminating" at interpreter exit is dropped (``engines/_quiet.py``).

Settings, defaults and the measurements behind them: ``docs/engines/opensees.md``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..constants import G
from ..errors import (ParameterError, check_choice, check_finite, check_int,
                      check_range)
from ._quiet import quiet_import
from .base import EngineBackend, EngineSettings
from .devices import DAMPER_MODELS, DeviceGeometry, PointForce, net_wrenches

__all__ = ["OpenseesBackend", "OpenseesSettings", "DAMPING_MODELS", "INTEGRATORS", "SEAT",
           "MAX_ITERATIONS", "MIN_TOLERANCE", "ROCKING_TOLERANCE", "SLIDING_TOLERANCE"]

#: Contact damping models: none; Rayleigh on the toes' committed stiffness; Rayleigh on mass.
DAMPING_MODELS = ("none", "stiffness", "mass")
#: The most Newton iterations per increment: OpenSees' counter is a C int (2^31 wrapped and
#: every run "did not converge at t = 0", reported as diverged); 25 converge every case.
MAX_ITERATIONS = 10_000
#: The smallest convergence tolerance [m]: the displacement-increment norm of a structure of
#: metres cannot fall below round-off (1e-300 never converged: "diverged" at t = 0).
MIN_TOLERANCE = 1e-12
#: The Newton test's tolerance [m] by default: without a scene friction (no sliding is
#: expected; the defaults measured in docs/engines/opensees.md), and with one (the contacts'
#: friction limit resolved: see ``OpenseesSettings.tolerance``).
ROCKING_TOLERANCE, SLIDING_TOLERANCE = 1e-8, 1e-10
#: Time integrators (OpenSees ``Newmark gamma beta`` or ``HHT alpha``).
INTEGRATORS = ("newmark", "hht")
_DEVICE_MODES = ("native", "forces")
#: Height [m] by which the lower node of every contact pair is placed above the upper one
#: (contacts closed from the first iteration; see the module docstring).
SEAT = 1e-10

# tags
_GRAVITY, _MOTION = 1, 2
_FIRST_SAT, _FIRST_FIXED = 100, 100000
_CONTACT0, _DASH0, _TENDON0, _DAMPER0 = 10000, 20000, 30000, 31000


@dataclass(frozen=True)
class OpenseesSettings(EngineSettings):
    """OpenSees settings. Every default is justified by a measurement in
    ``docs/engines/opensees.md``.

    dt : time step [s] (default 1e-3).
    friction : Coulomb coefficient of every contact [-] when the scene gives no friction
        (default 2, as pymunk's). A scene's ``[contact]`` friction replaces it
        (``docs/engines/README.md``).
    toe_stiffness : normal penalty stiffness of one interface [N/m] (split evenly over its
        springs), in [1e6, 1e15] (default 1e13: the beam's contact mode is annihilated every
        step; 1e11, the textbook order, lets the 175 t beam bounce off the column tops and the
        columns slide 3.6 mm).
    springs : contact springs per interface, an integer in [2, 101] (default 2, the corners).
    tangential_ratio : tangential / normal penalty stiffness [-], in [1e-3, 1e3] (default 1).
    damping : "none" (default), "stiffness" (Rayleigh damping proportional to the toes'
        committed stiffness, damping ratio ``damping_ratio`` of the toe's vertical mode under
        the lightest body) or "mass" (Rayleigh mass-proportional damping of the bodies,
        ``damping_ratio`` at the scene's frequency parameter p).
    damping_ratio : the damping ratio of ``damping`` [-], in [0, 10] (default 0.05; unused
        with "none").
    integrator : "newmark" (default) or "hht".
    gamma, beta : Newmark parameters (default 1.5 and 1: spectral radius 0 at high
        frequency); gamma in [0.5, 2], beta in [gamma / 2, 2] (unconditionally stable).
    hht_alpha : HHT alpha in OpenSees' convention, in [2/3, 1] (1: no numerical damping).
    member_ratio : stiffness of the rigid members / toe stiffness [-], in [1, 1e6]
        (default 100).
    iterations : Newton iterations per increment, an integer in [1, :data:`MAX_ITERATIONS` =
        1e4] (default 25).
    tolerance : displacement-increment norm of convergence [m], in [:data:`MIN_TOLERANCE` =
        1e-12, 1e-4], or None (default: 1e-8 when the scene gives no friction,
        :data:`SLIDING_TOLERANCE` = 1e-10 when it gives one); below round-off it never
        converges, above 1e-4 m = a tenth of the smallest length of a scene Newton stops at its
        first iterate: 1e300 reported a run ok. A displacement test does not see the force
        residual of the stiff contacts (1e-8 m on a 5e12 N/m tangential spring is 50 kN):
        at 1e-8 a squat block on mu = 0.2-0.5 never slides (Newton stops before the contact
        reaches its friction limit, the block sticks: 100 % short of Newmark's slip; 8 % short
        at mu = 0.8); at 1e-10 to 1e-12 it slides within 0.003 % of Newmark
        (``docs/engines/README.md``).
    halvings : how many times a non-converged increment is halved before the run is
        reported diverged, integer in [0, 10] (default 4: down to dt / 16).
    devices : "native" (default: corotational truss tendons removed at fracture, dampers per
        ``damper``) or "forces" (the shared point forces computed by the loop).
    damper : "distributed" (default), "couple" or "heel" (see the module docstring and
        :class:`~rockbench.engines.devices.DeviceGeometry`).

    Inherited (:class:`~rockbench.engines.base.EngineSettings`): output_dt, uplift_tol,
    max_penetration, max_sliding, energy_gain_tol.
    """

    dt: float = 1e-3
    friction: float = 2.0
    toe_stiffness: float = 1e13
    springs: int = 2
    tangential_ratio: float = 1.0
    damping: str = "none"
    damping_ratio: float = 0.05
    integrator: str = "newmark"
    gamma: float = 1.5
    beta: float = 1.0
    hht_alpha: float = 1.0
    member_ratio: float = 100.0
    iterations: int = 25
    tolerance: float | None = None
    halvings: int = 4
    devices: str = "native"
    damper: str = "distributed"

    def __post_init__(self) -> None:
        super().__post_init__()
        check_range("toe_stiffness", self.toe_stiffness, 1e6, 1e15)
        check_int("springs", self.springs, 2, 101)
        check_range("tangential_ratio", self.tangential_ratio, 1e-3, 1e3)
        check_choice("damping", self.damping, DAMPING_MODELS)
        check_range("damping_ratio", self.damping_ratio, 0.0, 10.0)
        check_choice("integrator", self.integrator, INTEGRATORS)
        g = check_range("gamma", self.gamma, 0.5, 2.0)
        b = check_finite("beta", self.beta)
        if not g / 2.0 - 1e-12 <= b <= 2.0:
            raise ParameterError("beta", self.beta, f"in [gamma / 2 = {g / 2.0:g}, 2]")
        check_range("hht_alpha", self.hht_alpha, 2.0 / 3.0, 1.0)
        check_range("member_ratio", self.member_ratio, 1.0, 1e6)
        check_int("iterations", self.iterations, 1, MAX_ITERATIONS)
        if self.tolerance is not None:
            check_range("tolerance", self.tolerance, MIN_TOLERANCE, 1e-4)
        check_int("halvings", self.halvings, 0, 10)
        check_choice("devices", self.devices, _DEVICE_MODES)
        check_choice("damper", self.damper, DAMPER_MODELS)


def _import_cause(e: BaseException) -> str:
    """The first cause of an import failure: openseespy replaces the loader's message
    ("libblas.so.3: cannot open shared object file") by "Failed to import openseespy on
    Linux", keeping the original as the exception's context."""
    while e.__cause__ is not None or e.__context__ is not None:
        e = e.__cause__ or e.__context__
    return f"{type(e).__name__}: {e}"


class NoConvergence(RuntimeError):
    """An OpenSees increment did not converge after every allowed halving of the step."""


class OpenseesBackend(EngineBackend):
    """The scene in OpenSees: rigid members, compression-only contact springs, implicit
    Newmark / HHT integration (see the module docstring)."""

    name: ClassVar[str] = "opensees"
    package: ClassVar[str] = "openseespy"
    Settings: ClassVar[type] = OpenseesSettings
    #: The contact settings a search may try (rockbench advise --full; engines/base.py).
    contact_variants: ClassVar[tuple] = (
        {"toe_stiffness": 1e11}, {"toe_stiffness": 1e12}, {"integrator": "hht", "hht_alpha": 0.9},
        {"damping": "stiffness"})

    @classmethod
    def _probe(cls) -> tuple[bool, str]:
        try:
            # its "Process 0 Terminating" at exit goes to /dev/null (engines/_quiet.py)
            ops = quiet_import("openseespy.opensees", at_exit=True)
            version = ops.version()
        except Exception as e:  # noqa: BLE001 - openseespy re-raises any import failure
            return False, f"openseespy does not import: {_import_cause(e)}"
        return True, f"OpenSeesPy {version}"

    @classmethod
    def remedy(cls, reason: str = "") -> str:
        if "libblas" in reason or "liblapack" in reason:
            return ("install the system BLAS that OpenSeesPy's Linux wheel links: "
                    "apt-get install libblas3 (Debian, Ubuntu) or dnf install blas (Fedora)")
        return super().remedy(reason)

    # --- building ---------------------------------------------------------------------------
    def _build(self) -> None:
        ops = quiet_import("openseespy.opensees", at_exit=True)

        cfg = self.settings
        specs = self.specs
        self._ops = ops
        self.halved = 0                 # increments that needed halving, over the run
        ops.wipe()
        ops.logFile("/dev/null", "-noEcho")
        ops.model("basic", "-ndm", 2, "-ndf", 3)
        ops.geomTransf("Corotational", 1)
        self._sat: list[tuple[int, int, float, float]] = []    # (body, node, lx, ly)
        self._next_sat, self._next_fixed, self._next_member = _FIRST_SAT, _FIRST_FIXED, 1
        self._kmem = cfg.member_ratio * cfg.toe_stiffness
        self._com = []
        for i, sp in enumerate(specs):
            ops.node(1 + i, sp.x, sp.y)
            ops.mass(1 + i, sp.mass, sp.mass, sp.inertia)
            self._com.append(1 + i)
        self._build_contacts()
        self._build_damping()
        self._build_devices()
        ops.timeSeries("Constant", _GRAVITY)
        ops.pattern("Plain", _GRAVITY, _GRAVITY)
        for node, sp in zip(self._com, specs):
            ops.load(node, 0.0, -sp.mass * G, 0.0)
        ops.timeSeries("Constant", _MOTION)
        self._pattern = False
        self._set_poses()
        ops.constraints("Plain")
        ops.numberer("RCM")
        ops.system("BandGeneral")
        ops.test("NormDispIncr", self._tolerance(), int(cfg.iterations), 0)
        ops.algorithm("Newton")
        if cfg.integrator == "newmark":
            ops.integrator("Newmark", float(cfg.gamma), float(cfg.beta))
        else:
            ops.integrator("HHT", float(cfg.hht_alpha))
        ops.analysis("Transient")
        self._last = self._read_state()

    def _tolerance(self) -> float:
        """The Newton test's tolerance in use [m] (``settings.tolerance``, or its default for
        the scene: :data:`SLIDING_TOLERANCE` with a scene friction, else
        :data:`ROCKING_TOLERANCE`)."""
        tol = self.settings.tolerance
        if tol is not None:
            return float(tol)
        return SLIDING_TOLERANCE if self.scene.contact.given else ROCKING_TOLERANCE

    def _interfaces(self) -> list[tuple[int | None, int, float, float, float]]:
        """(body below or None for the foundation, body above, y, x0, x1) of every contact
        interface at rest: block/column bases, then column tops under the beam."""
        specs = self.specs
        cols = [0, 2] if len(specs) == 3 else [0]
        out: list[tuple[int | None, int, float, float, float]] = []
        for i in cols:
            sp = specs[i]
            out.append((None, i, sp.y - sp.half_height, sp.x - sp.half_width,
                        sp.x + sp.half_width))
        for i in cols if len(specs) == 3 else []:
            sp = specs[i]
            out.append((i, 1, sp.y + sp.half_height, sp.x - sp.half_width,
                        sp.x + sp.half_width))
        return out

    def _build_contacts(self) -> None:
        ops, cfg = self._ops, self.settings
        n = int(cfg.springs)
        kn = cfg.toe_stiffness / n
        mu_base, mu_beam = self.friction_pairs
        self._contacts = []
        tag = _CONTACT0
        for below, above, y, x0, x1 in self._interfaces():
            mu = mu_base if below is None else mu_beam
            for x in np.linspace(x0, x1, n).tolist():
                upper = self._satellite(above, x, y)
                lower = (self._fixed(x, y + SEAT) if below is None
                         else self._satellite(below, x, y + SEAT))
                ops.element("zeroLengthContact2D", tag, upper, lower, kn,
                            kn * cfg.tangential_ratio, float(mu), "-normal", 0.0, 1.0)
                self._contacts.append(tag)
                tag += 1

    def _build_damping(self) -> None:
        ops, cfg = self._ops, self.settings
        if cfg.damping == "stiffness" and cfg.damping_ratio > 0.0:
            # zeroLengthContact2D has no Rayleigh damping: a parallel compression-only (ENT)
            # zeroLength of negligible stiffness eps k carries it, beta / eps on its committed
            # stiffness, i.e. a dashpot c = beta k active only while the toe is compressed
            n = int(cfg.springs)
            eps = 1e-3
            ops.uniaxialMaterial("ENT", 3, eps * cfg.toe_stiffness / n)
            dash = []
            for k, e in enumerate(self._contacts):
                upper, lower = ops.eleNodes(e)
                ops.element("zeroLength", _DASH0 + k, lower, upper, "-mat", 3, "-dir", 2,
                            "-doRayleigh", 1)
                dash.append(_DASH0 + k)
            m = min(sp.mass for sp in self.specs)
            beta = 2.0 * cfg.damping_ratio / math.sqrt(cfg.toe_stiffness / m)
            ops.region(1, "-ele", *dash, "-rayleigh", 0.0, 0.0, 0.0, beta / eps)
        elif cfg.damping == "mass" and cfg.damping_ratio > 0.0:
            ops.region(1, "-node", *self._com, "-rayleigh",
                       2.0 * cfg.damping_ratio * self.scene.p, 0.0, 0.0, 0.0)

    def _build_devices(self) -> None:
        ops, cfg, specs = self._ops, self.settings, self.specs
        self._device_eles: list[int] = []
        self._tendons: list[tuple[int, tuple[float, float], tuple[float, float], float]] = []
        self._dampers: DeviceGeometry | None = None
        sc = self.scene
        if not (sc.has_devices and self.native_devices and len(specs) == 3):
            return
        dv = sc.devices
        k = float(dv.tendon_stiffness or 0.0)
        c = float(dv.damping or 0.0)
        beam = specs[1]
        for j, i in enumerate((0, 2)):
            sp = specs[i]
            yb, yt = sp.y - sp.half_height, sp.y + sp.half_height
            if k > 0.0:
                length = yt - yb
                node_f = self._fixed(sp.x, yb)
                node_t = self._satellite(1, sp.x, yt)
                # tension-only elastic: E = k L (A = 1), no stiffness in compression
                ops.uniaxialMaterial("Elastic", 10 + j, k * length, 0.0, 0.0)
                ops.element("corotTruss", _TENDON0 + j, node_f, node_t, 1.0, 10 + j)
                self._device_eles.append(_TENDON0 + j)
                self._tendons.append((j, (sp.x, yb), (sp.x - beam.x, yt - beam.y), length))
            if c > 0.0 and cfg.damper == "heel":
                ops.uniaxialMaterial("Viscous", 20 + j, c, 1.0)
                for s in (-1, 1):
                    x = sp.x + s * sp.half_width
                    node_c = self._satellite(i, x, yb)
                    node_g = self._fixed(x, yb)
                    tag = _DAMPER0 + 10 * j + (s + 1)
                    ops.element("zeroLength", tag, node_g, node_c, "-mat", 20 + j, "-dir", 2)
                    self._device_eles.append(tag)
        if c > 0.0 and cfg.damper != "heel":
            # the shared damper forces only (the tendons are the trusses above)
            self._dampers = DeviceGeometry(sc, specs, cfg.damper)
            self._dampers.k = 0.0

    def _satellite(self, body: int, x: float, y: float) -> int:
        """A massless node of ``body`` at rest position (x, y) [m], tied to its centre of mass
        by a stiff corotational member."""
        ops = self._ops
        sp = self.specs[body]
        node = self._next_sat
        self._next_sat += 1
        ops.node(node, x, y)
        length = math.hypot(x - sp.x, y - sp.y)
        k = self._kmem
        ops.element("elasticBeamColumn", self._next_member, self._com[body], node, k * length,
                    1.0, k * length ** 3 / 3.0, 1)
        self._next_member += 1
        self._sat.append((body, node, x - sp.x, y - sp.y))
        return node

    def _fixed(self, x: float, y: float) -> int:
        node = self._next_fixed
        self._next_fixed += 1
        self._ops.node(node, x, y)
        self._ops.fix(node, 1, 1, 1)
        return node

    def _set_poses(self) -> None:
        """Displace every node rigidly to the initial poses (committed, at rest)."""
        ops = self._ops
        for node, sp, pose in zip(self._com, self.specs, self.poses0.tolist()):
            ops.setNodeDisp(node, 1, pose[0] - sp.x, "-commit")
            ops.setNodeDisp(node, 2, pose[1] - sp.y, "-commit")
            ops.setNodeDisp(node, 3, pose[2], "-commit")
        for body, node, lx, ly in self._sat:
            sp = self.specs[body]
            x, y, th = self.poses0[body].tolist()
            c, s = math.cos(th), math.sin(th)
            ops.setNodeDisp(node, 1, x + c * lx - s * ly - (sp.x + lx), "-commit")
            ops.setNodeDisp(node, 2, y + s * lx + c * ly - (sp.y + ly), "-commit")
            ops.setNodeDisp(node, 3, th, "-commit")

    # --- stepping ---------------------------------------------------------------------------
    def _step(self, gravity_x: float, forces: list[PointForce], gravity_y: float = -G) -> None:
        ops = self._ops
        if self._dampers is not None:
            forces = list(forces) + self._dampers.forces(self._last)[0]
        wrench = net_wrenches(forces, self._last).tolist() if forces else None
        if self._pattern:
            ops.remove("loadPattern", _MOTION)
            self._pattern = False
        vertical = gravity_y != -G      # the vertical ground motion, beyond gravity's pattern
        if gravity_x != 0.0 or wrench is not None or vertical:
            ops.pattern("Plain", _MOTION, _MOTION)
            ay = gravity_y + G if vertical else 0.0
            for i, (node, sp) in enumerate(zip(self._com, self.specs)):
                fx, fy, tz = wrench[i] if wrench is not None else (0.0, 0.0, 0.0)
                ops.load(node, sp.mass * gravity_x + fx, sp.mass * ay + fy, tz)
            self._pattern = True
        self._advance(float(self.settings.dt), 0)

    def _advance(self, dt: float, level: int) -> None:
        """One increment of ``dt`` [s]; if it does not converge, two of dt / 2, recursively, at
        most ``settings.halvings`` levels deep (converged sub-steps are kept)."""
        if self._ops.analyze(1, dt) == 0:
            return
        if level >= int(self.settings.halvings):
            raise NoConvergence(
                f"OpenSees did not converge {self._ops.getTime():.6g} s into the run (increment "
                f"{dt:.3g} s after {level} halvings of dt; settings iterations="
                f"{self.settings.iterations}, tolerance={self._tolerance():g} m)")
        self.halved += 1
        self._advance(0.5 * dt, level + 1)
        self._advance(0.5 * dt, level + 1)

    def _read_state(self) -> np.ndarray:
        ops = self._ops
        out = []
        for node, sp in zip(self._com, self.specs):
            d = ops.nodeDisp(node)
            v = ops.nodeVel(node)
            out.append((sp.x + d[0], sp.y + d[1], d[2], v[0], v[1], v[2]))
        return np.array(out, dtype=float)

    def _state(self) -> np.ndarray:
        self._last = self._read_state()
        return self._last

    # --- devices ----------------------------------------------------------------------------
    def _remove_devices(self) -> None:
        for tag in self._device_eles:
            self._ops.remove("element", tag)
        self._device_eles = []
        self._tendons = []
        self._dampers = None

    def _native_device_report(self, devices: DeviceGeometry, state: np.ndarray,
                              elongations: list[float]) -> tuple[list[float], list[float]]:
        """Truss tensions k (|T - F| - L) [N] for ``state`` and the damper forces C dc/dt [N]
        of the shared chord (every damper model acts with that force)."""
        tensions = [0.0, 0.0]
        beam = state[1]
        c, s = math.cos(beam[2]), math.sin(beam[2])
        for j, (fx, fy), (lx, ly), length in self._tendons:
            tx, ty = beam[0] + c * lx - s * ly, beam[1] + s * lx + c * ly
            tensions[j] = devices.k * max(0.0, math.hypot(tx - fx, ty - fy) - length)
        dampers = list(devices.forces(state)[2]) if devices.c > 0.0 else [0.0, 0.0]
        return tensions, dampers

    def _close(self) -> None:
        ops = getattr(self, "_ops", None)
        if ops is not None:
            ops.wipe()
        self._dampers = None

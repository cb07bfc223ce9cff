"""Terms of the equation of motion (Eq. 17) against quantities computed from the bodies' poses
only: kinetic energy (generalized inertia), potential energies (gravity, tendons), dissipated
power (dampers), and the statics of the mechanism (uplift threshold lambda, Eq. 20).

The poses come from :meth:`Mechanism.configuration` (CoM position [m] and rotation [rad] of each
body); velocities are finite differences in time along a trajectory phi(t), device geometry is
rebuilt from material points (tendon gaps at the joints, damper heel chord). SI units throughout.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
import rockbench as rb
from hypothesis import given, settings
from hypothesis import strategies as st

from rockbench.analytic.dynamics import Dynamics
from rockbench.scene.mechanism import geometric_limit
from rockbench.analytic.reference import Reference
from rockbench.constants import G
from rockbench.scene.devices import Devices
from rockbench.scene.scene import Scene, load_scene
from rockbench.scene.structure import Block, Frame
from strategies import dist, frames, material_point

FAST = settings(max_examples=30, deadline=None)

PAPER_ASYM = load_scene("paper-asymmetric").structure
PAPER_SYM = load_scene("paper-symmetric").structure
HOUSNER = load_scene("housner-block").structure
PAPER_DEVICES = load_scene("paper-asymmetric-hybrid").devices
STRUCTURES = {"block": HOUSNER, "symmetric": PAPER_SYM, "asymmetric": PAPER_ASYM}


# --- helpers ----------------------------------------------------------------------------------
def d1(f, x: float, h: float) -> float:
    """Richardson-extrapolated central difference (error O(h^4))."""
    c = lambda hh: (f(x + hh) - f(x - hh)) / (2.0 * hh)
    return (4.0 * c(0.5 * h) - c(h)) / 3.0


def masses(structure) -> list[tuple[float, float]]:
    """(mass [kg], centroidal inertia [kg m^2]) of each body, in mechanism order, from the
    geometry (rectangles; the beam from its radius of gyration)."""
    if isinstance(structure, Block):
        m = structure.density * structure.width * structure.height * structure.depth
        return [(m, m * (structure.width**2 + structure.height**2) / 12.0)]
    f = structure
    ml = f.density * f.column_width * f.column_height_left * f.depth
    mr = f.density * f.column_width * f.column_height_right * f.depth
    mb = f.mass_ratio * ml
    return [(ml, ml * (f.column_width**2 + f.column_height_left**2) / 12.0),
            (mb, mb * f.beam_gyration_radius**2),
            (mr, mr * (f.column_width**2 + f.column_height_right**2) / 12.0)]



def tendon_elongations(dyn: Dynamics, phi: float) -> tuple[float, float]:
    """Elongation [m] of each column's tendon from the poses: the gap opened at the base
    (foundation anchor to the column's base centre) plus the gap opened at the top (column's top
    centre to the beam point that touches it at rest)."""
    f = dyn.structure
    rest = dyn.configuration(0.0).bodies
    left, beam, right = dyn.configuration(phi).bodies
    out = []
    for col, rcol, x, ybase in ((left, rest[0], 0.0, 0.0), (right, rest[2], f.L, f.step)):
        base, top = (x, ybase), (x, f.column_height_left)
        gap_base = dist(material_point(col, rcol, base), base)
        gap_top = dist(material_point(col, rcol, top), material_point(beam, rest[1], top))
        out.append(gap_base + gap_top)
    return out[0], out[1]


def heel_chords(dyn: Dynamics, phi: float) -> tuple[float, float]:
    """Chord [m] between each column's uplifting heel corner and its rest position."""
    f, s = dyn.structure, dyn.direction
    rest = dyn.configuration(0.0).bodies
    left, _, right = dyn.configuration(phi).bodies
    heel_l, heel_r = (s * f.b, 0.0), (f.L + s * f.b, f.step)
    return (dist(material_point(left, rest[0], heel_l), heel_l),
            dist(material_point(right, rest[2], heel_r), heel_r))


def trajectory(direction: int, lim: float):
    """A smooth trajectory phi(t) [rad] inside the mechanism's range and its rate [rad/s]."""
    a = direction * 0.45 * min(lim, 1.2)
    return (lambda t: a * (1.0 + 0.8 * math.sin(1.3 * t)),
            lambda t: a * 0.8 * 1.3 * math.cos(1.3 * t))


devices = st.builds(Devices, tendon_stiffness=st.floats(1e5, 1e8),
                    tendon_length=st.floats(1.0, 20.0), damping=st.floats(1e4, 1e8),
                    fracture_strain=st.none())


# --- generalized inertia and velocity term ------------------------------------------------
def check_inertia(structure, direction: int, t: float) -> None:
    dyn = Dynamics(structure, direction)
    phi_of, rate_of = trajectory(direction, geometric_limit(dyn.mechanism))
    if abs(rate_of(t)) < 1e-3:
        t += 0.5
    body_data = masses(structure)

    def pose(tt, i, name):
        return getattr(dyn.configuration(phi_of(tt)).bodies[i], name)

    T = 0.0
    for i, (m, Ic) in enumerate(body_data):
        vx, vy, w = (d1(lambda tt, i=i, n=n: pose(tt, i, n), t, 1e-3) for n in ("x", "y", "theta"))
        T += 0.5 * m * (vx * vx + vy * vy) + 0.5 * Ic * w * w
    phi, rate = phi_of(t), rate_of(t)
    terms = dyn.terms(phi)
    assert terms.inertia == pytest.approx(2.0 * T / rate**2, rel=1e-7)
    assert terms.inertia > 0.0
    # J = 1/2 dI/dphi (Lagrange: d/dt(I phi') - 1/2 I' phi'^2 = I phi'' + 1/2 I' phi'^2)
    dI = d1(lambda p: dyn.terms(p).inertia, phi, 1e-4)
    scale = terms.inertia
    assert terms.velocity == pytest.approx(0.5 * dI, rel=1e-6, abs=1e-8 * scale)


@pytest.mark.parametrize("kind", list(STRUCTURES))
@pytest.mark.parametrize("direction", [1, -1])
@pytest.mark.parametrize("t", [0.0, 1.1, 2.0])
def test_inertia_is_twice_the_kinetic_energy_paper(kind, direction, t):
    check_inertia(STRUCTURES[kind], direction, t)


@FAST
@given(frame=frames, direction=st.sampled_from([1, -1]), t=st.floats(0.0, 5.0))
def test_inertia_is_twice_the_kinetic_energy_random(frame, direction, t):
    check_inertia(frame, direction, t)


def test_block_inertia_is_housners():
    """I_O = 4/3 m R^2 about the pivot, constant; J = 0."""
    for s in (1, -1):
        dyn = Dynamics(HOUSNER, s)
        for phi in (0.0, 0.3 * s, 1.0 * s):
            t = dyn.terms(phi)
            assert t.inertia == pytest.approx(4.0 / 3.0 * HOUSNER.mass * HOUSNER.R**2, rel=1e-13)
            assert t.velocity == pytest.approx(0.0, abs=1e-9 * t.inertia)


def test_symmetric_frame_inertia_is_makris_vassiliou():
    """Symmetric frame: I = 2 (4/3) m R^2 + m_BC (2R)^2 = (8/3) m R^2 (1 + 3 gamma), constant."""
    f = PAPER_SYM
    expected = 8.0 / 3.0 * f.mass_left * f.R0**2 * (1.0 + 3.0 * f.gamma)
    for s in (1, -1):
        dyn = Dynamics(f, s)
        for phi in (0.0, 0.1 * s, 0.8 * s):
            t = dyn.terms(phi)
            assert t.inertia == pytest.approx(expected, rel=1e-12)
            assert t.velocity == pytest.approx(0.0, abs=1e-9 * expected)


# --- gravity, ground, tendons, dampers ---------------------------------------------------------
def check_potential_terms(structure, devs, direction: int, frac: float) -> None:
    dyn = Dynamics(structure, direction, devs)
    lim = min(geometric_limit(dyn.mechanism), 1.4)
    phi = direction * max(frac, 0.01) * lim
    ms = [m for m, _ in masses(structure)]
    t = dyn.terms(phi)
    h = 1e-4
    # G: V_gravity / g = sum m_i y_i;  B: virtual work of -m_i u_g'' on dx_i
    dVg = d1(lambda p: sum(m * b.y for m, b in zip(ms, dyn.configuration(p).bodies)), phi, h)
    dX = d1(lambda p: sum(m * b.x for m, b in zip(ms, dyn.configuration(p).bodies)), phi, h)
    scale = sum(ms) * (structure.R if isinstance(structure, Block) else structure.R0)
    assert t.gravity == pytest.approx(dVg, rel=1e-7, abs=1e-9 * scale)
    assert t.ground == pytest.approx(-dX, rel=1e-7, abs=1e-9 * scale)
    if devs is None:
        assert t.tendon == 0.0 and t.damping == 0.0
        return
    k, c = devs.tendon_stiffness, devs.damping
    # K = dV_tendon/dphi with V_tendon = k/2 (e_left^2 + e_right^2)
    vt = lambda p: 0.5 * k * sum(e * e for e in tendon_elongations(dyn, p))
    dVt = d1(vt, phi, h)
    assert t.tendon == pytest.approx(dVt, rel=1e-6, abs=1e-9 * k * structure.R0**2)
    # D = dissipated power / phi'^2, power = C sum (d chord / dt)^2 along phi(t) = phi + 0.7 t
    rate = 0.7
    chord_rates = [d1(lambda tt, j=j: heel_chords(dyn, phi + rate * tt)[j], 0.0, h / rate)
                   for j in (0, 1)]
    power = c * sum(r * r for r in chord_rates)
    assert t.damping == pytest.approx(power / rate**2, rel=1e-6, abs=1e-9 * c * structure.R0**2)
    # without devices (fractured) both vanish, the rest is unchanged
    t0 = dyn.terms(phi, devices_intact=False)
    assert (t0.tendon, t0.damping) == (0.0, 0.0)
    assert t0[:4] == t[:4]


@pytest.mark.parametrize("kind", list(STRUCTURES))
@pytest.mark.parametrize("direction", [1, -1])
@pytest.mark.parametrize("frac", [0.05, 0.4, 0.9])
def test_potential_and_device_terms_paper(kind, direction, frac):
    structure = STRUCTURES[kind]
    devs = PAPER_DEVICES if isinstance(structure, Frame) else None
    check_potential_terms(structure, devs, direction, frac)


@FAST
@given(frame=frames, devs=devices, direction=st.sampled_from([1, -1]), frac=st.floats(0, 0.9))
def test_potential_and_device_terms_random(frame, devs, direction, frac):
    check_potential_terms(frame, devs, direction, frac)


def test_tendon_elongation_and_chord_of_the_device_state():
    """The model's tendon elongations and heel-chord rates are the pose-based ones."""
    for s in (1, -1):
        dyn = Dynamics(PAPER_ASYM, s, PAPER_DEVICES)
        for phi in (0.02 * s, 0.1 * s, 0.5 * s):
            ds = dyn.device_state(dyn.configuration(phi))
            el, er = tendon_elongations(dyn, phi)
            assert (ds.elong_left, ds.elong_right) == pytest.approx((el, er), rel=1e-12)
            rates = [d1(lambda p, j=j, dyn=dyn: heel_chords(dyn, p)[j], phi, 1e-4) for j in (0, 1)]
            assert (ds.dchord_left, ds.dchord_right) == pytest.approx(rates, rel=1e-7)


@pytest.mark.parametrize("kind", ["asymmetric", "symmetric"])
@pytest.mark.parametrize("direction", [1, -1])
def test_power_balance_of_the_equation_of_motion(kind, direction):
    """dE/dt = B u_g'' phi' - D phi'^2 for the energy T + V_gravity + V_tendon and the
    acceleration of Eq. 17: the acceleration, energy and the terms are mutually consistent."""
    dyn = Dynamics(STRUCTURES[kind], direction, PAPER_DEVICES)
    for phi, rate, ug in ((0.05, 0.3, 1.2), (0.4, -0.2, -3.0), (0.9, 0.05, 0.0)):
        phi *= direction
        acc = dyn.acceleration(phi, rate, ug)
        h = 1e-5
        def e(tt, phi=phi, rate=rate, acc=acc):
            return dyn.energy(phi + rate * tt + 0.5 * acc * tt * tt, rate + acc * tt)
        dEdt = d1(e, 0.0, h)
        t = dyn.terms(phi)
        expected = t.ground * ug * rate - t.damping * rate * rate
        scale = abs(t.ground * ug * rate) + abs(t.damping * rate**2) + abs(t.gravity * G * rate)
        assert dEdt == pytest.approx(expected, abs=1e-6 * scale)


# --- uplift threshold lambda (Eq. 20) against statics -------------------------------------------
def statics_lambda(structure, direction: int) -> tuple[float, np.ndarray]:
    """Solve the equilibrium of the bodies at rest, on the verge of rocking in ``direction``:
    unknowns are the reactions at the mechanism's four pivots (two components each; only the
    pivot A for a block) and lambda = u_g''/g; loads are the weights and the d'Alembert forces
    -m_i lambda g at the centres of mass. Returns (lambda, reactions [N])."""
    if isinstance(structure, Block):
        bodies = [(structure.mass, (0.0, structure.H))]
        pins = [((-direction * structure.b, 0.0), 0, None)]
    else:
        f = structure
        piv = f.pivots(direction)
        bodies = [(f.mass_left, f.com_left), (f.mass_beam, f.com_beam),
                  (f.mass_right, f.com_right)]
        # (point, body receiving +F, body receiving -F)
        pins = [(piv["A"], 0, None), (piv["B"], 0, 1), (piv["C"], 2, 1), (piv["D"], 2, None)]
    n = 2 * len(pins) + 1
    M = np.zeros((3 * len(bodies), n))
    rhs = np.zeros(3 * len(bodies))
    for j, (P, a, b) in enumerate(pins):
        for body, sign in ((a, 1.0), (b, -1.0)):
            if body is None:
                continue
            r = 3 * body
            M[r, 2 * j] += sign                       # Fx
            M[r + 1, 2 * j + 1] += sign               # Fy
            M[r + 2, 2 * j] += -sign * P[1]           # moment about the origin
            M[r + 2, 2 * j + 1] += sign * P[0]
    for i, (m, (gx, gy)) in enumerate(bodies):
        r = 3 * i
        M[r, -1] = -m * G                 # d'Alembert force -m lambda g in x
        rhs[r + 1] = m * G                # weight -m g in y, moved to the right-hand side
        M[r + 2, -1] = m * G * gy         # moment of -m lambda g at height gy
        rhs[r + 2] = m * G * gx           # moment of the weight
    sol = np.linalg.solve(M, rhs)
    return float(sol[-1]), sol[:-1]


def virtual_work_lambda(structure, direction: int) -> float:
    """lambda from the virtual work of gravity and d'Alembert forces over the mechanism's
    virtual displacement (finite differences of the CoM positions at rest)."""
    dyn = Dynamics(structure, direction)
    ms = [m for m, _ in masses(structure)]
    dy = d1(lambda p: sum(m * b.y for m, b in zip(ms, dyn.configuration(p).bodies)), 0.0, 1e-4)
    dx = d1(lambda p: sum(m * b.x for m, b in zip(ms, dyn.configuration(p).bodies)), 0.0, 1e-4)
    # -g sum m dy - lambda g sum m dx = 0
    return -dy / dx


@pytest.mark.parametrize("kind", list(STRUCTURES))
@pytest.mark.parametrize("direction", [1, -1])
def test_lambda_equals_statics_paper(kind, direction):
    structure = STRUCTURES[kind]
    lam_static, reactions = statics_lambda(structure, direction)
    lam_vw = virtual_work_lambda(structure, direction)
    scene = Scene(structure)
    lam = Reference(scene).lam[direction]
    assert lam == pytest.approx(Dynamics(structure, direction).uplift_threshold(), rel=1e-15)
    assert lam == pytest.approx(lam_static, rel=1e-12)
    assert lam == pytest.approx(lam_vw, rel=1e-8)
    assert direction * lam > 0.0          # a positive ground acceleration uplifts ccw
    # the contacts that remain at the verge of uplift are in compression
    ys = reactions[1::2]
    assert ys[0] > 0.0                     # foundation pushes the pivot A up
    if len(ys) == 4:
        assert ys[1] < 0.0 and ys[2] < 0.0  # the beam bears down on both column tops
        assert ys[3] > 0.0


@FAST
@given(frame=frames, direction=st.sampled_from([1, -1]))
def test_lambda_equals_statics_random(frame, direction):
    lam_static, _ = statics_lambda(frame, direction)
    lam = Dynamics(frame, direction).uplift_threshold()
    assert lam == pytest.approx(lam_static, rel=1e-10)
    assert lam == pytest.approx(virtual_work_lambda(frame, direction), rel=1e-7)


@pytest.mark.parametrize("structure", [HOUSNER, PAPER_SYM, Block(width=0.4, height=9.0),
                                       replace(PAPER_ASYM, column_height_right=7.0, mass_ratio=0.3,
                                               span=5.0, beam_width=9.0)],
                         ids=["housner", "paper-symmetric", "slender-block", "light-sym-frame"])
def test_lambda_of_block_and_symmetric_frame_is_tan_alpha(structure):
    ref = Reference(Scene(structure))
    assert ref.lam[1] == pytest.approx(math.tan(structure.alpha), rel=1e-12)
    assert ref.lam[-1] == pytest.approx(-math.tan(structure.alpha), rel=1e-12)


def test_asymmetric_lambdas_differ_and_bracket_tan_alpha():
    """Paper frame, H1/H = 0.8: both thresholds exceed tan(alpha) of the taller column but stay
    below tan(alpha1) of the shorter one."""
    ref = Reference(Scene(PAPER_ASYM))
    ta, ta1 = math.tan(PAPER_ASYM.alpha), math.tan(PAPER_ASYM.alpha1)
    for s in (1, -1):
        assert ta < abs(ref.lam[s]) < ta1
    assert abs(ref.lam[1]) != pytest.approx(abs(ref.lam[-1]), rel=1e-3)


# --- the critical angle in closed form where dV/dphi is one sinusoid ---------------------------
def _critical_cases():
    out = [(name, None) for name in rb.builtin_scenes()]
    # user structures the package never names: a squat and a slender block, an equal-column
    # frame with a heavy deck, an unequal one (the closed form must refuse it)
    out += [("housner-block", {"structure.width": 0.9, "structure.height": 1.1}),
            ("housner-block", {"structure.width": 0.2, "structure.height": 3.0}),
            ("paper-symmetric", {"structure.beam_mass": 4.0e6}),
            ("paper-asymmetric", {"structure.column_height_right": 4.0})]
    return out


@pytest.mark.parametrize("name,overrides", _critical_cases())
def test_the_closed_form_critical_angle_is_the_searched_one(name, overrides):
    """Where the gravity term (plus a symmetric frame's tendons) is one sinusoid in phi - a
    block, a frame whose columns stay parallel - the critical angle is atan2(b, a) + pi/2;
    elsewhere the form is refused and the scan with Brent's method decides. Both agree to
    round-off on every built-in scene and on structures written here."""
    import math

    from rockbench.analytic.reference import Reference, _sinusoid_root

    R = Reference(rb.load_scene(name, overrides))
    for s in (1, -1):
        for intact in (True, False):
            closed, searched = R.critical[(s, intact)], R._searched_critical_angle(s, intact)
            assert closed == searched or abs(closed - searched) <= 1e-12 * abs(searched)
    dyn, lim = R.dyn[1], R.fall[1]
    root = _sinusoid_root(lambda x: dyn.potential_gradient(x, False), lim)
    parallel = not name.startswith("paper-asymmetric")
    assert (root is not None) == parallel


def test_a_scene_s_reference_is_computed_once():
    """Every run, measurement and comparison of a scene shares one Reference (its critical and
    fracture angles are searched once per scene parameters, not once per run)."""
    from rockbench.analytic.reference import reference_of

    a = rb.load_scene("paper-asymmetric-hybrid")
    assert reference_of(a) is reference_of(rb.load_scene("paper-asymmetric-hybrid"))


def test_the_compiled_tableau_is_scipys_dop853():
    """The compiled path's tableau, read from scipy's file without importing scipy.integrate,
    is scipy's own table, entry for entry."""
    from scipy.integrate._ivp import dop853_coefficients as c

    from rockbench.analytic.tableau import dop853_tableau

    A, B, C, E3, E5, D, n = dop853_tableau()
    assert n == c.N_STAGES
    for mine, theirs in ((A, c.A), (B, c.B), (C, c.C), (E3, c.E3), (E5, c.E5), (D, c.D)):
        assert np.array_equal(mine, np.asarray(theirs, dtype=float))

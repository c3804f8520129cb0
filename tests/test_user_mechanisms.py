"""A user-declared Watt II six-bar (not in the catalog) loaded through ``sewgen.load``.

The mechanism: crank AB (pivot A at the origin) -> coupler BC -> ternary rocker DC (pivot D on ground) whose
arm pin E drives a second dyad: link EF -> output rocker GF (pivot G on ground). The loops split into two
RRR dyads (closed form); a second build solves them by Newton only. Checks: both builds agree, the loop
residual is at rounding level everywhere, and an independent numpy computation (circle intersection) of
the joints reproduces sewgen's positions and velocities. Also: the cache, loading from a .py file, and
declaration errors.
"""
from __future__ import annotations

import math
import textwrap

import numpy as np
import pytest

import sewgen
from sewgen.derive import DeclarationError
from sewgen.derive.model import Mechanism as Declaration

pytestmark = [pytest.mark.c, pytest.mark.derive]

# Declared once as source text so the very same declaration can be loaded as a function and from a file.
SIX_BAR_SOURCE = textwrap.dedent('''
    from sewgen.derive.model import Mechanism


    def declare():
        m = Mechanism("watt_six_bar", "Watt II six-bar: a crank-rocker whose rocker arm drives a second rocker.")
        r = m.length("crank", "10 mm", "crank AB")
        l2 = m.length("coupler", "40 mm", "coupler BC")
        l3 = m.length("rocker", "30 mm", "rocker DC")
        dx = m.length("rocker_pivot_x", "35 mm", "pivot D, x", signed=True)
        dy = m.length("rocker_pivot_y", "5 mm", "pivot D, y", signed=True)
        eu = m.length("arm_u", "-20 mm", "arm pin E in the rocker frame, u", signed=True)
        ev = m.length("arm_v", "10 mm", "arm pin E in the rocker frame, v", signed=True)
        l4 = m.length("link", "45 mm", "second coupler EF")
        l5 = m.length("output", "35 mm", "output rocker GF")
        gx = m.length("output_pivot_x", "10 mm", "pivot G, x", signed=True)
        gy = m.length("output_pivot_y", "40 mm", "pivot G, y", signed=True)
        crank = m.driven("crank", pivot=m.ground.at(0, 0), doc="input crank")
        coupler = m.link("coupler", doc="coupler BC", guess="60 deg")
        rocker = m.link("rocker", doc="ternary rocker D-C-E", guess="100 deg")
        link = m.link("link", doc="second coupler EF", guess="145 deg")
        output = m.link("output", doc="output rocker GF", guess="-120 deg")
        m.revolute(crank.at(r, 0), coupler.at(0, 0), name="B")
        m.revolute(m.ground.at(dx, dy), rocker.at(0, 0), name="D")
        m.revolute(coupler.at(l2, 0), rocker.at(l3, 0), name="C")
        m.revolute(rocker.at(eu, ev), link.at(0, 0), name="E")
        m.revolute(m.ground.at(gx, gy), output.at(0, 0), name="G")
        m.revolute(link.at(l4, 0), output.at(l5, 0), name="F")
        m.point("crank_pin", crank.at(r, 0), "B")
        m.point("coupler_pin", rocker.at(l3, 0), "C")
        m.point("arm_pin", rocker.at(eu, ev), "E")
        m.point("output_pin", output.at(l5, 0), "F")
        return m
''')

_ns: dict = {}
exec(compile(SIX_BAR_SOURCE, "<six_bar>", "exec"), _ns)
declare_six_bar = _ns["declare"]

# The defaults above, SI.
DIM = dict(crank=0.010, coupler=0.040, rocker=0.030, D=np.array([0.035, 0.005]), arm=np.array([-0.020, 0.010]),
           link=0.045, output=0.035, G=np.array([0.010, 0.040]))

PHI = sewgen.shaft_angles(5)  # 72 positions over a revolution
SPEED = 50.0  # rad/s
ACCEL = 30.0  # rad/s²


@pytest.fixture(scope="session")
def cache_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("sewgen_cache_user")


@pytest.fixture(scope="session")
def closed(cache_dir):
    return sewgen.load(declare_six_bar, closed_form=True, cache_dir=cache_dir)


@pytest.fixture(scope="session")
def newton_only(cache_dir):
    return sewgen.load(declare_six_bar, closed_form=False, cache_dir=cache_dir)


@pytest.fixture(scope="session")
def closed_motion(closed):
    return closed.solve(PHI, speed=SPEED, accel=ACCEL)


def _rot(theta, u, v):
    c, s = np.cos(theta), np.sin(theta)
    return np.stack([c * u - s * v, s * u + c * v], axis=-1)


def _circle_intersection(P, Q, l1, l2, sigma):
    """J at distance l1 from P and l2 from Q, left of the ray P->Q for sigma = +1 (numpy, vectorised)."""
    P, Q = np.broadcast_arrays(np.asarray(P, float), np.asarray(Q, float))
    d = Q - P
    dist = np.hypot(d[..., 0], d[..., 1])
    a = (l1**2 - l2**2 + dist**2) / (2 * dist)
    h = np.sqrt(l1**2 - a**2)
    ex = d / dist[..., None]
    ey = np.stack([-ex[..., 1], ex[..., 0]], axis=-1)  # ex turned +90°: "left"
    return P + a[..., None] * ex + sigma * h[..., None] * ey


def _wrap(a):
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def _all_finite(motion):
    return all(np.isfinite(a).all() for a in (motion.q, motion.qd, motion.qdd, motion.obs))


# -- the builds ------------------------------------------------------------------------------------------------

def test_builds_describe_themselves(closed, newton_only):
    assert closed.name == newton_only.name == "watt_six_bar"
    assert closed.closed_form is True
    assert newton_only.closed_form is False
    assert sorted(closed.coord_names) == ["coupler.angle", "link.angle", "output.angle", "rocker.angle"]
    assert closed.coord_names == newton_only.coord_names
    # two RRR dyads, closed at C and F, each with its own assembly sign
    assert [(b["joint"], b["kind"]) for b in closed.manifest["branches"]] == [("C", "rrr"), ("F", "rrr")]
    assert newton_only.branch_names == []
    assert closed.manifest["sizes"]["nq"] == 4
    assert closed.defaults()["arm_u"] == pytest.approx(-0.020)
    assert {c["name"]: c["guess"] for c in newton_only.manifest["coords"]}["output.angle"] == pytest.approx(
        math.radians(-120))


def test_closed_form_sweep_is_finite_and_complete(closed_motion):
    assert len(closed_motion) == len(PHI)
    assert _all_finite(closed_motion)
    # the crank turns a full revolution, the rockers only swing
    rocker = closed_motion.coord("rocker.angle").value
    output = closed_motion.coord("output.angle").value
    assert 0.3 < np.ptp(rocker) < 1.5
    assert 0.2 < np.ptp(output) < 1.0


def test_closed_and_newton_builds_agree(closed_motion, newton_only):
    mn = newton_only.solve(PHI, speed=SPEED, accel=ACCEL)
    assert _all_finite(mn)
    np.testing.assert_allclose(mn.q, closed_motion.q, rtol=0, atol=1e-9)
    np.testing.assert_allclose(mn.qd, closed_motion.qd, rtol=1e-8, atol=1e-8 * SPEED)
    np.testing.assert_allclose(mn.qdd, closed_motion.qdd, rtol=1e-7, atol=1e-7 * SPEED**2)
    for name in closed_motion.point_names:
        a, b = closed_motion.point(name), mn.point(name)
        np.testing.assert_allclose(b.x, a.x, atol=1e-11)
        np.testing.assert_allclose(b.y, a.y, atol=1e-11)
        np.testing.assert_allclose(b.vx, a.vx, atol=1e-9)
        np.testing.assert_allclose(b.ay, a.ay, atol=1e-6)


def test_newton_on_the_closed_build_agrees(closed, closed_motion):
    mn = closed.solve(PHI, speed=SPEED, accel=ACCEL, newton=True)
    np.testing.assert_allclose(mn.q, closed_motion.q, rtol=0, atol=1e-9)
    np.testing.assert_allclose(mn.obs, closed_motion.obs, rtol=1e-7, atol=1e-8)


@pytest.mark.parametrize("which", ["closed", "newton_build", "newton_flag"])
def test_loop_residual_is_at_rounding_level(which, closed, newton_only, closed_motion):
    if which == "closed":
        mech, motion = closed, closed_motion
    elif which == "newton_build":
        mech, motion = newton_only, newton_only.solve(PHI, speed=SPEED)
    else:
        mech, motion = closed, closed.solve(PHI, speed=SPEED, newton=True)
    worst = 0.0
    for q, phi in zip(motion.q, motion.phi):
        r, jac = mech.residual(q, phi)
        assert r.shape == (4,) and jac.shape == (4, 4)
        assert np.isfinite(jac).all()
        assert abs(np.linalg.det(jac)) > 0
        worst = max(worst, float(np.max(np.abs(r))))
    assert worst <= 1e-13, f"{which}: loop residual {worst:.3g} m"


def test_residual_detects_a_wrong_position(closed, closed_motion):
    """The residual check above can fail: a perturbed coordinate is far from closing."""
    q = closed_motion.q[7].copy()
    q[closed.coord_names.index("output.angle")] += 1e-6
    r, _ = closed.residual(q, PHI[7])
    assert np.max(np.abs(r)) > 1e-9


def test_first_loop_matches_circle_intersection(closed_motion):
    """Joint C from the crank pin and pivot D by numpy, against sewgen's point and coordinates."""
    B = _rot(PHI, DIM["crank"], 0.0)
    C = _circle_intersection(B, DIM["D"], DIM["coupler"], DIM["rocker"], +1)  # branch +1 at joint C
    pin = closed_motion.point("coupler_pin")
    np.testing.assert_allclose(pin.x, C[:, 0], rtol=0, atol=1e-13)
    np.testing.assert_allclose(pin.y, C[:, 1], rtol=0, atol=1e-13)
    th2 = np.arctan2(C[:, 1] - B[:, 1], C[:, 0] - B[:, 0])
    th3 = np.arctan2(C[:, 1] - DIM["D"][1], C[:, 0] - DIM["D"][0])
    np.testing.assert_allclose(_wrap(closed_motion.coord("coupler.angle").value - th2), 0, atol=1e-11)
    np.testing.assert_allclose(_wrap(closed_motion.coord("rocker.angle").value - th3), 0, atol=1e-11)


def test_second_dyad_matches_circle_intersection(closed_motion):
    """E from the first loop's rocker angle, then F as the intersection of circle(E, EF) and circle(G, GF)."""
    th3 = closed_motion.coord("rocker.angle").value
    E = DIM["D"] + _rot(th3, DIM["arm"][0], DIM["arm"][1])
    arm = closed_motion.point("arm_pin")
    np.testing.assert_allclose(arm.x, E[:, 0], atol=1e-13)
    np.testing.assert_allclose(arm.y, E[:, 1], atol=1e-13)
    F = _circle_intersection(E, DIM["G"], DIM["link"], DIM["output"], +1)  # branch +1 at joint F
    out = closed_motion.point("output_pin")
    np.testing.assert_allclose(out.x, F[:, 0], rtol=0, atol=1e-13)
    np.testing.assert_allclose(out.y, F[:, 1], rtol=0, atol=1e-13)
    th4 = np.arctan2(F[:, 1] - E[:, 1], F[:, 0] - E[:, 0])
    th5 = np.arctan2(F[:, 1] - DIM["G"][1], F[:, 0] - DIM["G"][0])
    np.testing.assert_allclose(_wrap(closed_motion.coord("link.angle").value - th4), 0, atol=1e-11)
    np.testing.assert_allclose(_wrap(closed_motion.coord("output.angle").value - th5), 0, atol=1e-11)
    # the other assembly of the second dyad is really another position (the branch sign matters)
    F_other = _circle_intersection(E, DIM["G"], DIM["link"], DIM["output"], -1)
    assert np.min(np.hypot(*(F_other - F).T)) > 1e-3


def test_second_dyad_velocities_match_velocity_loop(closed_motion):
    """The velocity loop of dyad E-F-G solved by numpy from the rocker's angular velocity."""
    th3 = closed_motion.coord("rocker.angle").value
    w3 = closed_motion.coord("rocker.angle").rate
    th4 = closed_motion.coord("link.angle").value
    th5 = closed_motion.coord("output.angle").value
    arm = _rot(th3, DIM["arm"][0], DIM["arm"][1])
    vE = w3[:, None] * np.stack([-arm[:, 1], arm[:, 0]], axis=-1)
    # vE + w4 * l4 * perp(e4) = w5 * l5 * perp(e5)
    A = np.empty((len(PHI), 2, 2))
    A[:, 0, 0], A[:, 1, 0] = -DIM["link"] * np.sin(th4), DIM["link"] * np.cos(th4)
    A[:, 0, 1], A[:, 1, 1] = DIM["output"] * np.sin(th5), -DIM["output"] * np.cos(th5)
    w = np.linalg.solve(A, -vE[..., None])[..., 0]
    np.testing.assert_allclose(closed_motion.coord("link.angle").rate, w[:, 0], rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(closed_motion.coord("output.angle").rate, w[:, 1], rtol=1e-9, atol=1e-9)
    out = closed_motion.point("output_pin")
    e5 = np.stack([np.cos(th5), np.sin(th5)], axis=-1)
    np.testing.assert_allclose(out.vx, -DIM["output"] * w[:, 1] * e5[:, 1], atol=1e-10)
    np.testing.assert_allclose(out.vy, DIM["output"] * w[:, 1] * e5[:, 0], atol=1e-10)


@pytest.mark.parametrize("build", ["closed", "newton_only"])
def test_rates_match_finite_differences(build, closed, newton_only):
    """q' and q'' (speed 1 rad/s, no shaft acceleration) are dq/dphi and dq'/dphi by central differences."""
    mech = closed if build == "closed" else newton_only
    phi, h = PHI[::3], 1e-5
    m0 = mech.solve(phi, speed=1.0, accel=0.0)
    mp = mech.solve(phi + h, speed=1.0, accel=0.0)
    mm = mech.solve(phi - h, speed=1.0, accel=0.0)
    fd1 = _wrap(mp.q - mm.q) / (2 * h)
    fd2 = (mp.qd - mm.qd) / (2 * h)
    np.testing.assert_allclose(m0.qd, fd1, rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(m0.qdd, fd2, rtol=1e-6, atol=1e-6)


def test_other_branch_by_sign_and_by_newton_guess(closed, newton_only):
    """branch={C: -1, F: -1} in closed form; the same assembly by Newton from solve(guess=...)."""
    phi = PHI[:12]
    other = closed.solve(phi, branch={"C": -1, "F": -1})
    default = closed.solve(phi)
    assert np.max(np.abs(_wrap(other.q - default.q))) > 0.1
    B = _rot(phi, DIM["crank"], 0.0)
    C = _circle_intersection(B, DIM["D"], DIM["coupler"], DIM["rocker"], -1)
    np.testing.assert_allclose(other.point("coupler_pin").x, C[:, 0], atol=1e-13)
    guess = {name: f"{math.degrees(v):.0f} deg" for name, v in zip(closed.coord_names, other.q[0])}
    mn = newton_only.solve(phi, guess=guess)
    np.testing.assert_allclose(_wrap(mn.q - other.q), 0, atol=1e-9)


# -- cache and loading -------------------------------------------------------------------------------------------

def test_first_load_compiled(closed, newton_only):
    assert closed.build_info["cached"] is False
    assert newton_only.build_info["cached"] is False
    assert closed.build_info["path"] != newton_only.build_info["path"]


def test_second_load_is_cached_and_identical(closed, closed_motion, cache_dir):
    again = sewgen.load(declare_six_bar, closed_form=True, cache_dir=cache_dir)
    assert again.build_info["cached"] is True
    assert again.build_info["path"] == closed.build_info["path"]
    m2 = again.solve(PHI, speed=SPEED, accel=ACCEL)
    for a, b in ((closed_motion.q, m2.q), (closed_motion.qd, m2.qd), (closed_motion.qdd, m2.qdd),
                 (closed_motion.obs, m2.obs)):
        assert np.array_equal(a, b)


def test_declaration_object_loads_from_cache(closed, cache_dir):
    decl = declare_six_bar()
    assert isinstance(decl, Declaration)
    again = sewgen.load(decl, cache_dir=cache_dir)
    assert again.build_info["cached"] is True
    assert again.build_info["path"] == closed.build_info["path"]


def test_changed_declaration_is_rebuilt(closed, cache_dir):
    def declare_longer_output():
        m = declare_six_bar()
        m.default_speed = "600 rpm"
        return m

    changed = sewgen.load(declare_longer_output, cache_dir=cache_dir)
    assert changed.build_info["cached"] is False
    assert changed.build_info["path"] != closed.build_info["path"]
    assert changed.default_speed == pytest.approx(600 * 2 * math.pi / 60)
    assert closed.default_speed == pytest.approx(1000 * 2 * math.pi / 60)


def test_load_from_py_file(tmp_path, closed, closed_motion, cache_dir):
    path = tmp_path / "my_six_bar.py"
    path.write_text(SIX_BAR_SOURCE)
    mech = sewgen.load(str(path), cache_dir=cache_dir)
    assert mech.name == "watt_six_bar"
    # same declaration, same generated code: the cache built from the function serves the file too
    assert mech.build_info["cached"] is True
    m = mech.solve(PHI, speed=SPEED, accel=ACCEL)
    assert np.array_equal(m.obs, closed_motion.obs)
    mech2 = sewgen.load(path, cache_dir=cache_dir)  # a Path works as well as a str
    assert mech2.build_info["cached"] is True


def test_load_missing_file_or_missing_declare(tmp_path, cache_dir):
    with pytest.raises(sewgen.BuildError, match="no mechanism file"):
        sewgen.load(str(tmp_path / "nope.py"), cache_dir=cache_dir)
    bad = tmp_path / "no_declare.py"
    bad.write_text("X = 1\n")
    with pytest.raises(sewgen.BuildError, match="declare"):
        sewgen.load(str(bad), cache_dir=cache_dir)
    with pytest.raises(sewgen.BuildError):
        sewgen.load(lambda: 42, cache_dir=cache_dir)


# -- declaration errors ------------------------------------------------------------------------------------------

def _four_bar_base(name: str):
    m = Declaration(name, "a four-bar used to provoke declaration errors")
    r = m.length("crank", "10 mm", "crank")
    crank = m.driven("crank", pivot=m.ground.at(0, 0))
    coupler = m.link("coupler")
    rocker = m.link("rocker")
    m.revolute(crank.at(r, 0), coupler.at(0, 0), name="B")
    m.revolute(m.ground.at(0.035, 0), rocker.at(0, 0), name="D")
    m.revolute(coupler.at(0.040, 0), rocker.at(0.030, 0), name="C")
    return m


def test_under_constrained_link_with_one_joint(cache_dir):
    def declare():
        m = _four_bar_base("dangling_link_mech")
        dangler = m.link("dangler", doc="pinned at one end only")
        m.revolute(m.body("rocker").at(-0.010, 0), dangler.at(0, 0), name="E")
        return m

    with pytest.raises((sewgen.BuildError, DeclarationError)) as info:
        sewgen.load(declare, cache_dir=cache_dir)
    msg = str(info.value)
    assert "dangling_link_mech" in msg
    assert "under-constrained" in msg


def test_unreachable_link(cache_dir):
    def declare():
        m = _four_bar_base("floating_link_mech")
        m.link("floater", doc="joined to nothing")
        return m

    with pytest.raises((sewgen.BuildError, DeclarationError)) as info:
        sewgen.load(declare, cache_dir=cache_dir)
    assert "floating_link_mech" in str(info.value)
    assert "floater" in str(info.value)


def test_duplicate_name(cache_dir):
    def declare():
        m = _four_bar_base("duplicate_name_mech")
        m.link("coupler", doc="a second body named like the first")
        return m

    with pytest.raises((sewgen.BuildError, DeclarationError)) as info:
        sewgen.load(declare, cache_dir=cache_dir)
    assert "duplicate_name_mech" in str(info.value)
    assert "coupler" in str(info.value)


def test_duplicate_parameter_name():
    m = Declaration("dup_param_mech", "")
    m.length("crank", "10 mm", "crank")
    with pytest.raises(DeclarationError, match="dup_param_mech"):
        m.length("crank", "12 mm", "crank again")


def test_bad_mechanism_name():
    with pytest.raises(DeclarationError, match="Not_Snake"):
        Declaration("Not_Snake", "")


@pytest.mark.parametrize("declare_crank, words", [
    (lambda m: m.length("crank", 12, "crank"), ["'crank'", "bare number 12", '"12 mm"', "12 m"]),
    (lambda m: m.driven("crank", pivot=m.ground.at(12, 0)), ["'ground'", "bare number 12", "12 m"]),
    (lambda m: m.ground.line(angle=90), ["bare number 90", "90 rad", '"90 deg"']),
])
def test_a_bare_number_meant_in_mm_or_deg_is_refused_before_anything_compiles(tmp_path, declare_crank, words):
    """``m.length("crank", 12)`` was a 12 m crank: a vague assembly error after a 7.8 s compile. A parameter's
    default carries its unit; a bare coordinate is SI, and one beyond 1 m (or a turn) is refused at once."""
    def declare():
        m = Declaration("bare_number_mech", "a declaration with a number written without its unit")
        declare_crank(m)
        return m

    with pytest.raises((sewgen.BuildError, DeclarationError)) as info:
        sewgen.load(declare, cache_dir=tmp_path)
    msg = str(info.value)
    assert "bare_number_mech" in msg and all(w in msg for w in words), msg
    assert not list(tmp_path.rglob("*.so")) and not list(tmp_path.rglob("*.c"))  # nothing derived or compiled

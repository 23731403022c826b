"""CRM execution: docs/model.md section 7 worked cases and hand-computed cases."""

import math

import numpy as np
import pytest

from crmgrasp import CRM, Config, Contact, CrmgraspError, Disc, Error, Hand, Polygon, min_friction, observe
from crmgrasp.model.geometry import regular_polygon
from crmgrasp.model.palm import palm_point

from .test_geometry import U_SHAPE

# --------------------------------------------------------- docs/model.md section 7


@pytest.fixture
def near(task):
    return task.hand.contact(task.obj, a=(-0.15, -0.02), b=(-0.10, -0.05))


@pytest.fixture
def far(task):
    return task.hand.contact(task.obj, a=(-0.15, -0.02), b=(0.00, -0.05))


def test_worked_observation(near):
    assert near == Config(Contact(-0.15, -0.02, 1.0, 0.0), Contact(-0.10, -0.05, -0.0, 1.0))
    rho, m_a, m_b = observe(near)
    assert rho == 2.0
    assert m_a == pytest.approx(0.05, abs=1e-15)
    assert m_b == pytest.approx(-0.03, abs=1e-15)


def test_worked_c1_opposes(task, near):
    out = task.hand.execute(task.obj, near, task.actions[0])
    assert out.error is Error.NONE
    assert out.config.a == Contact(-0.10, 0.05, 0.0, -1.0)
    assert out.config.b == near.b
    assert min_friction(out.config) == 0.0
    assert task.is_success(out.config)
    assert out.path[0] == (-0.15, -0.02) and out.path[1] == pytest.approx((-0.16, -0.02))
    assert out.path[2] == pytest.approx((-0.10, 0.11)) and out.path[3] == (-0.10, 0.05)


def test_worked_c2_aperture(task, near):
    out = task.hand.execute(task.obj, near, task.actions[1])
    assert out.error is Error.APERTURE and out.config is near


def test_worked_c1_palm(task, far):
    out = task.hand.execute(task.obj, far, task.actions[0])
    assert out.error is Error.PALM and out.config is far
    assert palm_point(Config(Contact(0, 0.05, 0, -1), far.b), 0.12) == pytest.approx((-0.12, 0.0))


def test_worked_c4_moves_toward_corner(task, far):
    out = task.hand.execute(task.obj, far, task.actions[3])
    assert out.error is Error.NONE
    assert out.config.b == Contact(-0.08, -0.05, -0.0, 1.0)
    assert out.config.a == far.a


# --------------------------------------------------------------- a disc
DISC = Disc(0.05)
HAND = Hand(aperture=0.16, palm_depth=0.12, backoff=0.01)
DISC_START = Config(Contact(-0.05, 0.0, 1.0, 0.0), Contact(0.0, -0.05, 0.0, 1.0))


def test_disc_opposition_reaches_antipodal():
    out = HAND.execute(DISC, DISC_START, CRM("a", "b", 0.0))
    assert out.error is Error.NONE
    assert out.config.a == pytest.approx(Contact(0.0, 0.05, 0.0, -1.0))
    assert min_friction(out.config) == 0.0


def test_disc_offset_right_hits_palm():
    # a lands at (0.03, 0.04) with n = (-0.6, -0.8); n_a . u = 0.316 > 0: palm error
    out = HAND.execute(DISC, DISC_START, CRM("a", "b", 0.03))
    assert out.error is Error.PALM and out.config is DISC_START
    assert out.path[3] == pytest.approx((0.03, 0.04))


def test_disc_offset_left_lands_exactly():
    out = HAND.execute(DISC, DISC_START, CRM("a", "b", -0.03))
    assert out.error is Error.NONE
    assert out.config.a == pytest.approx(Contact(-0.03, 0.04, 0.6, -0.8))
    assert min_friction(out.config) == pytest.approx(1.0 / 3.0)


def test_disc_goal_line_out_of_reach():
    # (a, a, -0.15): line y = 0.15 is 0.20 from b, beyond the 0.16 aperture
    out = HAND.execute(DISC, DISC_START, CRM("a", "a", -0.15))
    assert out.error is Error.APERTURE and out.goal is None


# ------------------------------------------------------------ a hexagon
HEX = regular_polygon(6, 0.1)
H = math.sqrt(3) / 20  # half height, 0.0866 m
HEX_START = Config(Contact(-0.075, -H / 2, math.sqrt(3) / 2, 0.5), Contact(0.0, -H, 0.0, 1.0))


def test_hexagon_start_inside_is_aperture_error():
    # chord reaches y = -H + 0.16 = 0.0734 < H: the start point is inside
    out = HAND.execute(HEX, HEX_START, CRM("a", "b", 0.0))
    assert out.error is Error.APERTURE
    assert out.goal.at(out.goal.t_hi) == pytest.approx((0.0, 0.16 - H))


def test_hexagon_opposition_with_wider_hand():
    wide = Hand(aperture=0.25, palm_depth=0.12)
    assert wide.feasible(HEX, HEX_START) is Error.NONE
    out = wide.execute(HEX, HEX_START, CRM("a", "b", 0.0))
    assert out.error is Error.NONE
    assert out.config.a.point == pytest.approx((0.0, H))
    assert out.config.a.normal == pytest.approx((0.0, -1.0))
    assert min_friction(out.config) == 0.0


# ------------------------------------------------------------ a U shape
U = Polygon(U_SHAPE)
U_START = Config(Contact(0.05, 0.2, 0.0, -1.0), Contact(0.0, 0.15, 1.0, 0.0))


def test_u_opposition_enters_inner_side():
    assert HAND.feasible(U, U_START) is Error.NONE
    out = HAND.execute(U, U_START, CRM("a", "b", 0.0))
    assert out.error is Error.NONE
    assert out.config.a == pytest.approx(Contact(0.1, 0.15, -1.0, 0.0))  # inner face of the left arm
    assert out.path[2] == pytest.approx((0.16, 0.15))  # start point in the gap


def test_u_start_inside_right_arm():
    out = Hand(aperture=0.25, palm_depth=0.12).execute(U, U_START, CRM("a", "b", 0.0))
    assert out.error is Error.APERTURE  # start (0.25, 0.15) is inside the right arm
    assert U.contains(out.goal.at(out.goal.t_hi))


def test_u_approach_line_misses():
    out = HAND.execute(U, U_START, CRM("a", "b", -0.08))  # line y = 0.23 passes above the U
    assert out.error is Error.APERTURE
    assert out.goal is not None and out.path[-1] == U_START.a.point


# ------------------------------------------------------------ bad input
def test_bad_crm_and_hand_inputs(task, near):
    with pytest.raises(CrmgraspError, match="unknown contact label 'e'"):
        CRM("e", "a", 0.0)
    with pytest.raises(CrmgraspError, match="names contact 'c', but the hand has contacts a, b"):
        task.hand.execute(task.obj, near, CRM("c", "a", 0.0))
    with pytest.raises(CrmgraspError, match="a hand has 2 to 4 contacts, got 1"):
        Hand(aperture=0.1, palm_depth=0.1, contacts=1)
    with pytest.raises(CrmgraspError, match="finite"):
        CRM("a", "b", float("nan"))
    with pytest.raises(CrmgraspError, match="beyond r_max"):
        task.hand.execute(task.obj, near, CRM("a", "a", 0.5))
    with pytest.raises(CrmgraspError, match="c,f,r"):
        CRM.parse("a,b")
    with pytest.raises(CrmgraspError, match="aperture must be > 0"):
        Hand(aperture=0.0, palm_depth=0.1)
    with pytest.raises(CrmgraspError, match="palm_depth must be >= 0"):
        Hand(aperture=0.1, palm_depth=-1)
    with pytest.raises(CrmgraspError, match="rng"):
        from crmgrasp import SensorNoise

        task.hand.execute(task.obj, near, task.actions[0], noise=SensorNoise(0.01, 0.0))
    with pytest.raises(CrmgraspError, match="unit vector"):
        Contact.make((0, 0), (1, 1))


def test_noise_moves_goal_line_but_contact_stays_on_true_boundary(task, near):
    import dataclasses

    from crmgrasp import SensorNoise

    noise = SensorNoise(math.radians(3), 0.002)
    tolerant = dataclasses.replace(task.hand, palm_normal_tol=math.sin(math.radians(10)))
    out = tolerant.execute(task.obj, near, task.actions[0], noise=noise, rng=np.random.default_rng(3))
    assert out.error is Error.NONE
    assert out.config.a.y == pytest.approx(0.05) and out.config.a.normal == (0.0, -1.0)
    assert out.config.a.x != -0.10  # the sensed frame shifted the goal line
    assert 0.0 < min_friction(out.config) < 0.2
    # with the default 1e-9 tolerance the same misaligned landing is a palm error
    strict = task.hand.execute(task.obj, near, task.actions[0], noise=noise, rng=np.random.default_rng(3))
    assert strict.error is Error.PALM


def test_palm_normal_tol_validation():
    with pytest.raises(CrmgraspError, match="palm_normal_tol must be < 1"):
        Hand(0.1, 0.1, palm_normal_tol=1.0)

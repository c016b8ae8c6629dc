"""The seed paper's worked examples (Hu & Tang 2004, tables 1-4) and Hou et al. 2005, with errata.

g is taken as 10 as in the paper: 0.0517 t/m -> 517 N/m, 0.13 t/m -> 1300 N/m.
Printed values carry ~5 significant digits (the paper's search tolerance), so a printed value is
matched to its last printed digit; the errata check the exact value and the printed one's offset.
"""

import math

import pytest

from catenary_monitor import solve

DOCK_W, DOCK_H = 1300.0, 20.85


def printed(value: float, text: str) -> bool:
    """True when value rounds to the printed decimal string (within one unit of its last digit)."""
    digits = len(text.split('.')[1]) if '.' in text else 0
    return abs(value - float(text)) <= 10.0**-digits


def test_table1_matches_r_8963():
    """Table 1: every printed number matches R = 89.63 kN (wind + current, no wave drift)."""
    r = solve(517.0, 80.0, horizontal=89.63e3)
    assert abs(r.min_anchor_distance - 160.74) <= 0.01  # the paper's search steps x by 0.01 m
    assert printed(r.top_tension / 1e3, '130.9')
    # The paper evaluates L, G and beta at its last x = 160.74 m, where y = 80.00 m.
    a, x = 89.63e3 / 517.0, 160.74
    assert abs(2 * a * math.sinh(x / (2 * a)) ** 2 - 80.0) < 0.02  # its stop test on y
    assert printed(a * math.sinh(x / a), '184.78')
    assert printed(a * math.sinh(x / a) * 517.0 / 1e4, '9.553')  # chain weight G in t (g = 10)
    assert printed(math.degrees(math.atan(math.sinh(x / a))), '46.82')
    assert printed(r.top_angle_deg, '46.82')


def test_erratum_table1_stated_load():
    """With the stated R = 101.59 kN the answer differs: x = 171.79 m, T = 142.95 kN, SF 8.9."""
    r = solve(517.0, 80.0, horizontal=101.59e3, mbl=1270e3)
    assert printed(r.min_anchor_distance, '171.79')
    assert printed(r.top_tension / 1e3, '142.95')
    assert printed(r.suspended_length, '194.52')
    assert printed(r.top_angle_deg, '44.71')
    assert printed(r.safety_factor, '8.9')
    assert r.min_anchor_distance - 160.74 > 11.0  # the printed table is off by more than 11 m
    assert not printed(1270e3 / r.top_tension, '9.7')


def test_table2_pretension():
    r = solve(DOCK_W, DOCK_H, horizontal=372e3, anchor_distance=120.0)
    assert abs(r.min_anchor_distance - 108.5839) <= 1e-4
    assert abs(r.top_tension / 1e3 - 399.1048) <= 2e-3
    assert abs(r.suspended_length - 111.2086) <= 2e-4
    assert abs(r.suspended_length * DOCK_W / 1e4 - 14.45711) <= 3e-5
    assert abs(r.top_angle_deg - 21.23776) <= 1e-4
    assert r.anchor_margin > 0 and r.uplift_force == 0.0  # 120 m is enough


def test_table3_typhoon_line11():
    r = solve(DOCK_W, DOCK_H, horizontal=1584.6e3, anchor_distance=121.06)
    assert abs(r.anchor_angle_deg - 6.9537) <= 3e-4  # printed value stopped short (erratum)
    assert abs(r.uplift_force / 1e3 - 193.264) <= 1e-2
    assert abs(r.top_tension / 1e3 - 1623.448) <= 3e-3
    assert abs(r.suspended_length - 122.8915) <= 2e-4
    assert abs(r.top_angle_deg - 12.5597) <= 5e-4


def test_erratum_table3_top_angle():
    """beta is printed 15.5595 deg in most rows; exactly it is 12.559 deg (one row: 12.5597)."""
    r = solve(DOCK_W, DOCK_H, horizontal=1584.6e3, anchor_distance=121.06)
    assert printed(r.top_angle_deg, '12.559')
    assert abs((15.5595 - r.top_angle_deg) - 3.0) < 1e-3  # a leading digit off by 3


def test_erratum_table3_search_stopped_short():
    """The paper's stepping search stopped ~1e-5 short: exact alpha, F and T differ in the last
    digits."""
    r = solve(DOCK_W, DOCK_H, horizontal=1584.6e3, anchor_distance=121.06)
    assert printed(r.anchor_angle_deg, '6.95347')
    assert printed(r.uplift_force / 1e3, '193.258')
    assert printed(r.top_tension / 1e3, '1623.446')
    assert 5e-3 < 193.264 - r.uplift_force / 1e3 < 7e-3
    assert 1e-4 < 6.9537 - r.anchor_angle_deg < 3e-4


def test_table4_measured_tension():
    r = solve(DOCK_W, DOCK_H, tension=1623.5e3)
    assert abs(r.horizontal_tension / 1e3 - 1596.4) <= 0.05
    assert abs(r.suspended_length - 227.2494) <= 5e-4
    assert abs(r.suspended_length * DOCK_W / 1e4 - 29.54242) <= 1e-4
    assert abs(r.top_angle_deg - 10.48439) <= 5e-5


def test_erratum_table4_anchor_distance():
    """x is printed 255.9719 m; the exact answer is 225.97 m (two digits transposed)."""
    r = solve(DOCK_W, DOCK_H, tension=1623.5e3)
    assert printed(r.min_anchor_distance, '225.97')
    assert abs((255.9719 - r.min_anchor_distance) - 30.0) < 1e-3
    assert r.suspended_length >= r.min_anchor_distance  # L >= span; the printed x violates it
    assert 227.2494 < 255.9719


def test_erratum_equation2_printed_cot():
    """Eq. (2) expanded prints 1/tg(alpha): it would blow up at alpha = 0, where L is finite."""
    r = solve(DOCK_W, DOCK_H, horizontal=372e3)
    a = 372e3 / DOCK_W
    x = r.min_anchor_distance
    assert math.isclose(r.suspended_length, a * math.sinh(x / a), rel_tol=1e-12)  # tan(alpha) form


@pytest.mark.parametrize(
    'lm,h,lying,fh',
    [
        (20.0, 15.0, '0.563', '127.33'),
        (20.0, 13.0, '4.68', '63.09'),
        (21.0, 15.0, '2.90', '85.51'),
        (21.0, 13.0, '6.59', '37.14'),
    ],
)
def test_hou_2005_table(lm, h, lying, fh):
    """Hou et al. 2005: w = 25 kgf/m, dm = 11 m (units consistent in kgf and m)."""
    r = solve(25.0, h, chain_length=lm, anchor_distance=11.0)
    assert printed(r.grounded_length, lying)
    assert abs(r.horizontal_tension - float(fh)) <= 0.011  # printed truncated to 0.01 kgf
    assert r.uplift_force == 0.0

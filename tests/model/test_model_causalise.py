"""Causalisation: BLT ordering, algebraic loops, and the errors for models it cannot solve."""

import casadi as ca
import numpy as np
import pytest
from spindlebench.core.errors import SpindlebenchError
from spindlebench.model.causalise import solve_explicitly, strongly_connected_blocks


def symbols(*names):
    return [ca.SX.sym(name) for name in names]


def test_blocks_come_after_what_they_depend_on():
    # 0 depends on 1, 1 on 2 and 3, 2 and 3 form a loop
    blocks = strongly_connected_blocks([[1], [2, 3], [3], [2]])
    assert blocks == [[2, 3], [1], [0]]


def test_chain_with_an_algebraic_loop_is_solved_exactly():
    # a massless junction between two conductors: j = (G1*Ta + G2*Tb)/(G1+G2)
    ta, tb, g1, g2 = symbols("Ta", "Tb", "G1", "G2")
    j, q1, q2, out = symbols("j", "q1", "q2", "out")
    residuals = ca.vertcat(
        q1 - g1 * (ta - j),  # flow into the junction from a
        q2 - g2 * (j - tb),  # flow out to b
        q1 - q2,  # the junction stores nothing
        out - 2 * q2,
    )
    unknowns = ca.vertcat(j, q1, q2, out)
    solution, simultaneous = solve_explicitly(residuals, unknowns, ["j", "q1", "q2", "out"])
    assert simultaneous, "the junction, q1 and q2 form a simultaneous block"
    f = ca.Function("f", [ca.vertcat(ta, tb, g1, g2)], [solution])
    j_val, q1_val, q2_val, out_val = np.array(f([300.0, 280.0, 2.0, 3.0])).ravel()
    assert j_val == pytest.approx((2 * 300 + 3 * 280) / 5)
    assert q1_val == pytest.approx(q2_val)
    assert out_val == pytest.approx(2 * 2.0 * (300 - j_val))


def test_nonlinear_in_an_earlier_unknown_is_fine():
    (t,) = symbols("T")
    nu, q = symbols("nu", "q")
    residuals = ca.vertcat(nu - 22 * ca.exp(-0.03 * (t - 313.15)), q - 0.1 * nu**0.67)
    solution, simultaneous = solve_explicitly(residuals, ca.vertcat(nu, q), ["nu", "q"])
    assert not simultaneous
    value = float(ca.Function("f", [t], [solution[1]])(313.15))
    assert value == pytest.approx(0.1 * 22**0.67)


def test_unknown_appearing_nonlinearly_in_its_own_equation_is_refused():
    (x,) = symbols("x")
    with pytest.raises(SpindlebenchError, match="nonlinear"):
        solve_explicitly(ca.vertcat(x**2 - 4), ca.vertcat(x), ["x"])


def test_unbalanced_model_names_the_unknown_without_equation():
    a, b = symbols("a", "b")
    with pytest.raises(SpindlebenchError, match=r"not balanced.*no equation for: b"):
        solve_explicitly(ca.vertcat(a - 1), ca.vertcat(a, b), ["a", "b"])


def test_structurally_singular_model_is_refused():
    a, b = symbols("a", "b")
    residuals = ca.vertcat(a - 1, 2 * a - 2)  # two equations for a, none for b
    with pytest.raises(SpindlebenchError, match="structurally singular"):
        solve_explicitly(residuals, ca.vertcat(a, b), ["a", "b"])


def test_a_loop_through_a_port_is_solved_at_the_size_it_has_without_the_port():
    # the junction above, with conductor b reached through a sub-assembly's port (pT, pQ):
    # the alias equations pT = j, pQ = -q2 and q1 = -pQ are substituted: a 2 x 2 solve, not 5 x 5
    ta, tb, g1, g2 = symbols("Ta", "Tb", "G1", "G2")
    j, q1, q2, pt, pq = symbols("j", "q1", "q2", "pT", "pQ")
    residuals = ca.vertcat(
        q1 - g1 * (ta - j),
        q2 - g2 * (pt - tb),
        pt - j,  # the port's temperature is the junction's
        pq + q2,  # the port's flow (into the assembly) is what leaves through b
        q1 + pq,  # the junction stores nothing
    )
    unknowns = ca.vertcat(j, q1, q2, pt, pq)
    solution, simultaneous = solve_explicitly(residuals, unknowns, ["j", "q1", "q2", "pT", "pQ"])
    assert simultaneous == [2]
    f = ca.Function("f", [ca.vertcat(ta, tb, g1, g2)], [solution])
    j_val, q1_val, q2_val, pt_val, pq_val = np.array(f([300.0, 280.0, 2.0, 3.0])).ravel()
    assert j_val == pytest.approx((2 * 300 + 3 * 280) / 5)
    assert (pt_val, pq_val, q2_val) == (j_val, -q1_val, pytest.approx(q1_val))

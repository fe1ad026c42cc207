"""ortools and highspy each ship a libhighs.so.1; they must agree or the second import fails.
Each order is tried in a fresh interpreter (a process imports a shared library once)."""

import subprocess
import sys

import pytest

ORDERS = [
    "import highspy\nfrom ortools.sat.python import cp_model\nimport cvxpy",
    "from ortools.sat.python import cp_model\nimport highspy\nimport cvxpy",
]


@pytest.mark.parametrize("imports", ORDERS)
def test_solver_libraries_load_together(imports):
    code = imports + (
        "\nh = highspy.Highs()\nh.silent()\n"
        "m = cp_model.CpModel()\nx = m.new_bool_var('x')\nm.minimize(-1.0 * x)\n"
        "assert cp_model.CpSolver().solve(m) == cp_model.OPTIMAL\n"
        "print('ok')\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0 and "ok" in out.stdout, out.stderr[-2000:]

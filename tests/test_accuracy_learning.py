"""agents.accuracy_learning: its one-step error measure follows each method's order, and its outputs (CSVs, chart,
page) are written from a run's rows, the summary saying what the numbers say."""

import numpy as np
import pytest

from agents import accuracy_learning as al

SWING = "connenv/Swing-v0"


@pytest.fixture(scope="module")
def swing_states():
    X, A = al.sample_states(SWING, 32)
    return X, A, al.one_step(SWING, {}, X, A)


def test_one_step_error_is_zero_for_the_default_and_falls_as_the_methods_order(swing_states):
    X, A, reference = swing_states
    assert np.ptp(X[:, 0]) > 0.05  # the states are spread along episodes, not all the reset's
    assert al.one_step_error(SWING, {}, X, A, reference) == {"error_median": 0.0, "error_p90": 0.0,
                                                              "failed_share": 0.0}  # fmt: skip
    euler = [al.one_step_error(SWING, {"integrator": "euler", "substeps": n}, X, A, reference)["error_median"]
             for n in (1, 2, 4)]  # fmt: skip
    # n substeps of h = dt/n: n local errors O(h²), the step's error O(dt²/n): halved by each doubling (first order)
    assert euler[0] > 1e-3
    np.testing.assert_allclose([euler[0] / euler[1], euler[1] / euler[2]], 2.0, rtol=0.05)
    rk4 = [al.one_step_error(SWING, {"integrator": "rk4", "substeps": n}, X, A, reference)["error_median"]
           for n in (1, 2)]  # fmt: skip
    np.testing.assert_allclose(rk4[0] / rk4[1], 16.0, rtol=0.1)  # fourth order
    assert rk4[0] < 1e-4 * euler[0]


def rows_of_a_run():
    base = {"env": "Swing-v0", "kwargs": "{}", "seeds": 5, "timesteps": 4096, "compile_seconds": 30.0,
            "episodes": 8, "training_failures": 0, "error_p90": 0.0, "failed_share": 0.0}  # fmt: skip
    made = [("euler", 10.0, 0.2, 0.1, 0.3, 3e-2), ("rk4", 12.0, 0.95, 0.9, 1.0, 2e-7),
            ("exact (default)", 11.0, 0.97, 0.93, 1.0, 0.0)]  # fmt: skip
    rows = [{**base, "stepper": s, "train_seconds": t, "success": m, "success_low": lo, "success_high": hi,
             "return": m, "return_low": lo, "return_high": hi, "error_median": e} for s, t, m, lo, hi, e in made]  # fmt: skip
    nan = float("nan")  # a stepper failing most single steps is not trained
    rows.append({**rows[0], "stepper": "euler×2", "timesteps": 0, "train_seconds": nan, "compile_seconds": nan,
                 "success": nan, "success_low": nan, "success_high": nan, "training_failures": nan,
                 "failed_share": 0.75, "note": "it fails 75% of single steps"})  # fmt: skip
    jax_rows = [{"env": "Swing-v0", "trained_on": t, "physics": p, "return": r, "success": 0.5, "failed": f,
                 "energy_gained": g} for t, p, r, f, g in [("euler", "euler", 1.5, 0.4, 1.2),
                                                          ("euler", "exact (default)", 0.3, 0.0, 0.0),
                                                          ("exact (default)", "euler", 1.1, 0.1, 0.4),
                                                          ("exact (default)", "exact (default)", 1.0, 0.0, 0.0)]]  # fmt: skip
    return rows, jax_rows


def test_outputs_are_written_from_the_rows(tmp_path):
    rows, jax_rows = rows_of_a_run()
    args = al.parse_args(["--quick", "--runs", str(tmp_path)])
    al.write_outputs(rows, jax_rows, args.docs, args, 60.0)
    assert al.read_csv(args.docs / "precision" / al.CSV_NAME)[0]["success"] == pytest.approx(0.2)
    assert len(al.read_csv(args.docs / "precision" / al.JAX_CSV_NAME)) == 4
    assert (args.docs / "precision" / al.PNG_NAME).read_bytes()[:4] == b"\x89PNG"
    page = (args.docs / al.PAGE).read_text()
    assert "As good on the exact physics: rk4." in page and "Not good enough: euler (20%)." in page
    assert "trained on Euler return 1.5 on Euler (success 50%, 40% of the episodes cut short" in page
    assert "Euler's error is worth +1.2 of return to the Euler-trained policies and +0.1 to the exact" in page
    assert "1.2 J per episode under the Euler-trained policies, 0.4 J under the exact (default)-trained ones" in page
    assert "| Swing-v0 | euler | 10 | 30 | 20% [10%, 30%] |" in page
    assert "Not trained, as it fails most single steps (the env's divergence check): euler×2." in page
    assert "| Swing-v0 | euler×2 | not trained: it fails 75% of single steps |" in page
    al.main(["--quick", "--runs", str(tmp_path), "--page"])  # the page again from the CSVs alone
    again = (args.docs / al.PAGE).read_text()
    assert again.replace("; 1 min in all on this machine", "") == page.replace("; 1 min in all on this machine", "")
    assert "In short: Worse than the default's: Swing-v0 (euler). A cheaper model stopped being usable where it " \
           "fails the env's divergence check: Swing-v0's euler×2 (75% of single steps)." in page  # fmt: skip

"""Adversarial Python inputs (fuzz_child.py) in a child interpreter: no crash, one-line
errors, no non-finite output. The child has a timeout so that a hang fails the test (it is
no performance limit)."""

import json
import subprocess
import sys

import pytest

HERE = __import__("pathlib").Path(__file__).resolve().parent


@pytest.mark.parametrize("seed", [1, 2])
def test_fuzz_finds_no_crash_and_no_bad_error(root, tmp_path, seed):
    done = subprocess.run(
        [sys.executable, str(HERE / "fuzz_child.py"), str(root), str(tmp_path), str(seed), "150"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, f"the interpreter died ({done.returncode}): {done.stderr[-3000:]}"
    report = json.loads(done.stdout.strip().splitlines()[-1])
    assert report["violations"] == [], "\n".join(report["violations"])
    counts = report["counts"]
    # the generator reached every branch: refused sets, invalid and valid scenes, runs, texts
    assert counts["set_refused"] > 10 and counts["invalid"] > 5 and counts["validated"] > 5, counts
    assert counts["runs"] + counts["run_failed"] > 0 and counts["texts"] >= 20, counts

"""The Python fuzz cases, run by test_fuzz.py in a child interpreter (a crash of the
extension then fails the test instead of killing pytest).

Usage: python fuzz_child.py ROOT WORKDIR SEED CASES

A deterministic generator (seeded) builds:
- `Scene.set` calls on the paper scene with known, misspelt and made-up dotted keys and
  values of every kind (numbers at the edges, NaN and infinities, strings, lists, nested
  dicts, NumPy values, cycles, deep nesting), each followed by validation and, for a share
  of the valid ones, a short run;
- text inputs (`Scene.from_toml`, `Scene.load`, `link_frequencies`) from mutated shipped
  files: truncated, with bytes flipped, lines repeated, brackets nested without end;
- kinematics on arrays of edge values (NaN, infinities, 1e300) and odd shapes.

Laws checked: no crash (the parent sees the exit status); every error is a flexprr error
(`SceneError`, `RunError`, `KinematicsError`) or a `KeyError`/`TypeError` of the API, its
text one line; a `SceneError` from `set` names the key given; a successful run has only
finite numbers in its tables. Prints one JSON line: counts and the violations found.
"""

import json
import math
import random
import sys
import traceback

import numpy as np

import flexprr

KEYS = [
    "name",
    "description",
    "links.length",
    "links.modes",
    "links.section.thickness",
    "links.section.height",
    "links.section.kind",
    "links.material.youngs_modulus",
    "links.material.density",
    "links.basis.kind",
    "links.basis.elements",
    "links.basis.ends",
    "machine.layout",
    "machine.alpha_deg",
    "machine.alpha_deg.1",
    "machine.platform_side",
    "machine.half_travel",
    "machine.platform_mass",
    "machine.platform_inertia",
    "machine.slider_mass",
    "machine.legs",
    "trajectory.radius",
    "trajectory.frequency",
    "trajectory.centre",
    "trajectory.centre.0",
    "trajectory.phi_deg",
    "trajectory.kind",
    "model.formulation",
    "model.coupling",
    "model.damping",
    "model.axial_force",
    "model.elements",
    "integrator.method",
    "integrator.rtol",
    "integrator.atol",
    "integrator.max_step",
    "integrator.max_steps",
    "time.start",
    "time.end",
    "time.output_step",
    "time.stops",
    "output.requests",
    "output.deflection_xi",
    "output.plots",
    # made up or malformed
    "links.nope",
    "nope",
    "links..length",
    "links.length.x",
    "machine.alpha_deg.9",
    "machine.alpha_deg.x",
    ".links",
    "links.",
    "",
    "a" * 300,
]


def deep(levels):
    top = cur = []
    for _ in range(levels):
        nxt = []
        cur.append(nxt)
        cur = nxt
    return top


def cyclic():
    d = {"a": 1.0}
    d["self"] = d
    return d


VALUES = [
    lambda r: r.choice([0, 1, -1, 3, 60, 61, 2**31, 2**63 - 1, -(2**63)]),
    lambda r: r.choice([0.0, -0.0, 1e-300, 1e300, 0.002, 0.2, 20.0, -5.0, 1e9]),
    lambda r: r.choice([math.nan, math.inf, -math.inf]),
    lambda r: r.uniform(-1.0, 1.0) * 10 ** r.randint(-6, 6),
    lambda r: r.choice([True, False]),
    lambda r: r.choice(["", "x", "abm", "paper", "consistent", "hermite", "../../x", "a" * 1000, "kinematics"]),
    lambda r: [r.uniform(-1, 1) for _ in range(r.randint(0, 5))],
    lambda r: [r.choice(["kinematics", "deflections", "energies", "nothing"]) for _ in range(r.randint(0, 4))],
    lambda r: {"kind": r.choice(["uniform", "tapered", "sine", "circle", "x"]), "thickness": 0.002},
    lambda r: np.float64(r.uniform(0.0, 1.0)),
    lambda r: np.arange(r.randint(0, 4), dtype=float),
    lambda r: np.int32(r.randint(-5, 5)),
    lambda r: None,
    lambda r: object(),
    lambda r: cyclic(),
    lambda r: deep(r.choice([10, 40, 5000])),
    lambda r: 10**40,
]

API_ERRORS = (flexprr.SceneError, flexprr.RunError, flexprr.KinematicsError, KeyError, TypeError)


class Fuzz:
    def __init__(self, root, work, seed):
        self.root = root
        self.work = work
        self.rng = random.Random(seed)
        self.violations = []
        self.counts = {"set": 0, "set_refused": 0, "validated": 0, "invalid": 0, "runs": 0, "run_failed": 0, "texts": 0}
        self.base = flexprr.Scene.load(f"{root}/configs/paper_f20.toml")
        self.base.set("output.plots", False).set("output.compare_without_axial_force", False)

    def violation(self, case, what):
        self.violations.append(f"{case}: {what}")

    def check_error(self, case, e):
        if not isinstance(e, API_ERRORS):
            self.violation(case, f"unexpected {type(e).__name__}: {e!r}")
        elif "\n" in str(e):
            self.violation(case, f"error of more than one line: {str(e)!r}")

    def scene_case(self, case):
        scene = self.base.copy()
        for _ in range(self.rng.randint(1, 3)):
            key = self.rng.choice(KEYS)
            value = self.perturbed(scene, key)
            self.counts["set"] += 1
            before = scene.to_toml()
            try:
                scene.set(key, value)
            except flexprr.SceneError as e:
                self.counts["set_refused"] += 1
                self.check_error(case, e)
                if not e.key.startswith(key) and key:
                    self.violation(case, f"set({key!r}) refused under key {e.key!r}")
                if scene.to_toml() != before:
                    self.violation(case, f"refused set({key!r}) changed the scene")
            except Exception as e:  # noqa: BLE001 - any other type is the violation
                self.check_error(case, e)
        try:
            scene.validate()
        except Exception as e:  # noqa: BLE001
            self.counts["invalid"] += 1
            self.check_error(case, e)
            return
        self.counts["validated"] += 1
        if self.rng.random() < 0.25:
            self.run_short(case, scene)

    def perturbed(self, scene, key):
        """Often the current value scaled (the type right, the size anything), else any value."""
        try:
            current = scene.get(key)
        except (KeyError, TypeError):
            current = None
        if isinstance(current, float) and self.rng.random() < 0.5:
            return current * self.rng.choice([0.0, -1.0, 0.5, 0.9, 1.1, 2.0, 10.0, 1e6])
        return self.rng.choice(VALUES)(self.rng)

    def run_short(self, case, scene):
        """A short run: every number in its tables finite, or a one-line error."""
        try:
            start = float(scene["time"].get("start", 0.0))
            end = min(float(scene["time.end"]), start + 0.004)
            scene.set("time.end", end).set("output.requests", ["kinematics", "deflections", "axial_forces"])
            result = flexprr.run(scene)
        except Exception as e:  # noqa: BLE001
            self.counts["run_failed"] += 1
            self.check_error(case, e)
            if isinstance(e, flexprr.RunError):
                self.check_finite(case, e.partial)
            return
        self.counts["runs"] += 1
        self.check_finite(case, result)

    def check_finite(self, case, result):
        for name in result.tables:
            data = result.table(name).to_numpy()
            if not np.all(np.isfinite(data)):
                self.violation(case, f"non-finite values in table {name}")

    def text_case(self, case):
        source = self.rng.choice(["configs/paper_f20.toml", "configs/link_paper.toml", "configs/pick_and_place.toml"])
        text = open(f"{self.root}/{source}", encoding="utf-8").read()
        mutate = self.rng.randint(0, 5)
        if mutate == 0:
            text = text[: self.rng.randint(0, len(text))]
        elif mutate == 1:
            at = self.rng.randint(0, len(text) - 1)
            text = text[:at] + self.rng.choice("[]{}=\"'#\n.,0x") + text[at + 1 :]
        elif mutate == 2:
            lines = text.splitlines()
            line = self.rng.choice(lines)
            text = "\n".join(lines + [line] * self.rng.randint(1, 3))
        elif mutate == 3:
            text += "\nx = " + "[" * self.rng.choice([100, 10000, 200000])
        elif mutate == 4:
            text = "a = {" * 5000 + text
        else:
            text = text.replace("0.", self.rng.choice(["-0.", "nan", "1e400", "0x", "inf"]), 1)
        self.counts["texts"] += 1
        path = f"{self.work}/mutant_{case}.toml"
        with open(path, "w", encoding="utf-8") as f:
            f.write(text)
        for call in (
            lambda: flexprr.Scene.from_toml(text, name="mutant").validate(),
            lambda: flexprr.Scene.load(path).validate(),
            lambda: flexprr.link_frequencies(path),
        ):
            try:
                out = call()
            except Exception as e:  # noqa: BLE001
                self.check_error(case, e)
                continue
            if isinstance(out, dict) and not np.all(np.isfinite(out["frequencies_hz"])):
                self.violation(case, "non-finite link frequencies")


def kinematics_case(fuzz, case):
    """Kinematics on arrays with edge values and odd shapes: a result with finite numbers,
    or a KinematicsError or ValueError (shape) of one line."""
    rng = fuzz.rng
    shape = rng.choice([(3,), (rng.randint(0, 6), 3), (2, 2), (1, 1, 3)])
    edge = [0.0, -0.0, 1e-300, 1e300, math.nan, math.inf, 0.05, -0.05, 0.785]
    values = np.array([rng.choice(edge) if rng.random() < 0.3 else rng.uniform(-0.08, 0.08) for _ in range(int(np.prod(shape)))]).reshape(shape)
    for call in (flexprr.inverse_kinematics, flexprr.forward_kinematics, flexprr.singularity):
        try:
            out = call(values)
        except (flexprr.KinematicsError, ValueError) as e:
            if "\n" in str(e):
                fuzz.violation(case, f"error of more than one line: {str(e)!r}")
            continue
        except Exception as e:  # noqa: BLE001
            fuzz.violation(case, f"unexpected {type(e).__name__}: {e!r}")
            continue
        arrays = out.values() if isinstance(out, dict) else [out]
        if not all(np.all(np.isfinite(a)) for a in arrays):
            fuzz.violation(case, f"{call.__name__}: non-finite output")


def main():
    root, work, seed, cases = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
    fuzz = Fuzz(root, work, seed)
    for case in range(cases):
        try:
            if case % 6 == 5:
                kinematics_case(fuzz, case)
            elif case % 3 == 2:
                fuzz.text_case(case)
            else:
                fuzz.scene_case(case)
        except Exception:  # noqa: BLE001 - a bug of the fuzzer or an escaped error
            fuzz.violation(case, traceback.format_exc(limit=3))
    print(json.dumps({"counts": fuzz.counts, "violations": fuzz.violations[:50]}))


if __name__ == "__main__":
    main()

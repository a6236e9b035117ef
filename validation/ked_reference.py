"""Independent KED (kineto-elasto-dynamics) model of the paper's 3-PRR scene, numpy/scipy only,
and its comparison with the coupled Exudyn model.

Two formulations (docs/model.md section 6):

* ``paper``: eq. 16 with the F_fg term, diagonal K_p, axial force of eq. 12
  (P0 = -(F_B.u) cos(b - a)):
      M eta'' + (Kf + Kp) eta = -m rho'' sin(a - b) int psi - m l b'' int xi psi
                                + m rho' b' cos(a - b) int psi
* ``consistent``: no F_fg, centrifugal softening -b'^2 M, joint-reaction axial force
  (P0 = -F_B.e, model.md section 5), full K_p:
      M eta'' + (Kf + Kp - b'^2 M) eta = -m rho'' sin(a - b) int psi - m l b'' int xi psi

Sine modes psi_j = sin(j pi xi), r per link (default 3), eta(0) = 0, eta'(0) = 0, rigid
motion and axial forces from the rigid inverse dynamics of `scene.py` (model.md sections 3-4).

Usage:
    python3 ked_reference.py            # check vs the reference state, compare with data/*.csv
    python3 ked_reference.py --modes 5  # more modes
"""

import argparse
import json
import os
import sys

import numpy as np
from scipy.integrate import solve_ivp

from scene import Scene, axial_force_coefficients, rigid_inverse_dynamics

HERE = os.path.dirname(os.path.abspath(__file__))


class ModalIntegrals:
    """Integrals of the sine modes on xi in [0, 1] (Gauss-Legendre, 64 points per half-wave)."""

    def __init__(self, modes):
        self.modes = modes
        xi, wq = np.polynomial.legendre.leggauss(64 * modes)
        xi = 0.5 * (xi + 1.0)
        wq = 0.5 * wq
        j = np.arange(1, modes + 1)[:, None]
        psi = np.sin(j * np.pi * xi)
        dpsi = j * np.pi * np.cos(j * np.pi * xi)
        ddpsi = -((j * np.pi) ** 2) * psi
        self.int_psi = psi @ wq  # int psi_j
        self.int_xi_psi = psi @ (wq * xi)  # int xi psi_j
        self.mass = (psi * wq) @ psi.T  # int psi_j psi_k
        self.bending = (ddpsi * wq) @ ddpsi.T  # int psi_j'' psi_k''
        self.g = [(dpsi * (wq * xi**n)) @ dpsi.T for n in range(3)]  # G_n
        self.psi_mid = np.sin(j[:, 0] * np.pi * 0.5)


class KedModel:
    """KED equations of the three links for one formulation (model.md section 6)."""

    def __init__(self, scene, modes=3, formulation="paper"):
        if formulation not in ("paper", "consistent"):
            raise ValueError(f"unknown formulation {formulation!r}")
        self.scene = scene
        self.r = modes
        self.formulation = formulation
        self.ints = ModalIntegrals(modes)
        m, l = scene.link_mass, scene.link_length
        self.mass = m * self.ints.mass
        self.k_flex = scene.bending_stiffness / l**3 * self.ints.bending
        self.evaluations = 0

    def stiffness_and_force(self, t):
        """Per link: total stiffness K (r x r) and forcing F (r), plus P(0), P(l)."""
        sc = self.scene
        m, l = sc.link_mass, sc.link_length
        legs, f_b, _f_c, _f_a = rigid_inverse_dynamics(sc, t)
        form = "paper" if self.formulation == "paper" else "joint"
        out = []
        for i, k in enumerate(legs):
            p0, p1, p2 = axial_force_coefficients(sc, k, i, f_b[i], form)
            kp = p0 / l * self.ints.g[0] + p1 * self.ints.g[1] + p2 * l * self.ints.g[2]
            a_minus_b = sc.guide_angles[i] - k.beta
            force = (
                -m * k.rho_dd * np.sin(a_minus_b) * self.ints.int_psi
                - m * l * k.beta_dd * self.ints.int_xi_psi
            )
            if self.formulation == "paper":
                kp = np.diag(np.diag(kp))
                force = force + m * k.rho_d * k.beta_d * np.cos(a_minus_b) * self.ints.int_psi
                stiff = self.k_flex + kp
            else:
                stiff = self.k_flex + kp - k.beta_d**2 * self.mass
            out.append((stiff, force, p0, p0 + p1 * l + p2 * l * l))
        return out

    def rhs(self, t, y):
        """First-order form: y = (eta (3r), eta' (3r))."""
        self.evaluations += 1
        r = self.r
        eta = y[: 3 * r]
        dy = np.empty_like(y)
        dy[: 3 * r] = y[3 * r :]
        for i, (stiff, force, _pb, _pc) in enumerate(self.stiffness_and_force(t)):
            s = slice(i * r, (i + 1) * r)
            dy[3 * r + i * r : 3 * r + (i + 1) * r] = np.linalg.solve(
                self.mass, force - stiff @ eta[s]
            )
        return dy

    def solve(self, t_end, t_eval, rtol=1e-12, atol=1e-15):
        """Integrate from eta(0) = 0, eta'(0) = 0 with DOP853."""
        y0 = np.zeros(6 * self.r)
        sol = solve_ivp(
            self.rhs, (0.0, t_end), y0, method="DOP853", rtol=rtol, atol=atol, t_eval=t_eval
        )
        if not sol.success:
            raise RuntimeError(f"KED {self.formulation}: integration failed: {sol.message}")
        return sol

    def midpoint_deflection(self, y):
        """w_i(l/2, t) for each link from the modal coordinates (rows: time)."""
        r = self.r
        eta = np.atleast_2d(y)[:, : 3 * r]
        return np.stack([eta[:, i * r : (i + 1) * r] @ self.ints.psi_mid for i in range(3)], axis=1)


def check_reference_state(path, modes=3):
    """Paper formulation at f = 20 Hz vs the reference state at t = 0.2 s (tests/data)."""
    with open(path) as fh:
        ref = json.load(fh)
    scene = Scene(frequency=20.0)
    model = KedModel(scene, modes, "paper")
    sol = model.solve(ref["t_s"], [ref["t_s"]], rtol=1e-13, atol=1e-16)
    got = sol.y[:, -1]
    want = np.asarray(ref["state"])
    n = 3 * modes
    rel_eta = np.linalg.norm(got[:n] - want[:n]) / np.linalg.norm(want[:n])
    rel_deta = np.linalg.norm(got[n:] - want[n:]) / np.linalg.norm(want[n:])
    return rel_eta, rel_deta


def load_coupled(path):
    """Read a coupled-model CSV (header row, comma separated) into a dict of columns."""
    with open(path) as fh:
        header = fh.readline().strip().split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    return {name: data[:, k] for k, name in enumerate(header)}


def compare(freq, modes, data_dir):
    """Relative L2 errors of KED mid-point deflections vs the coupled model, and axial forces."""
    coupled = load_coupled(os.path.join(data_dir, f"coupled_f{int(freq)}.csv"))
    t = coupled["t_s"]
    w_c = np.stack([coupled[f"w_mid_{i}_m"] for i in (1, 2, 3)], axis=1)
    pb_c = np.stack([coupled[f"P_B_{i}_N"] for i in (1, 2, 3)], axis=1)
    pc_c = np.stack([coupled[f"P_C_{i}_N"] for i in (1, 2, 3)], axis=1)
    scene = Scene(frequency=freq)
    result = {"f_Hz": freq, "modes": modes}
    for form in ("paper", "consistent"):
        model = KedModel(scene, modes, form)
        sol = model.solve(t[-1], t)
        w_k = model.midpoint_deflection(sol.y.T)
        err = np.linalg.norm(w_k - w_c) / np.linalg.norm(w_c)
        per_link = [
            float(np.linalg.norm(w_k[:, i] - w_c[:, i]) / np.linalg.norm(w_c[:, i]))
            for i in range(3)
        ]
        pb_k = np.zeros_like(pb_c)
        pc_k = np.zeros_like(pc_c)
        for n, tn in enumerate(t):
            for i, (_s, _f, pb, pc) in enumerate(model.stiffness_and_force(tn)):
                pb_k[n, i], pc_k[n, i] = pb, pc
        result[form] = {
            "rel_L2_w_mid_all_links": float(err),
            "rel_L2_w_mid_per_link": per_link,
            "max_abs_w_mid_ked_m": float(np.max(np.abs(w_k))),
            "axial_force_model": "eq. 12 (paper)" if form == "paper" else "joint reaction",
            "rms_P_B_coupled_minus_ked_N": [
                float(np.sqrt(np.mean((pb_c[:, i] - pb_k[:, i]) ** 2))) for i in range(3)
            ],
            "rms_P_C_coupled_minus_ked_N": [
                float(np.sqrt(np.mean((pc_c[:, i] - pc_k[:, i]) ** 2))) for i in range(3)
            ],
            "rms_P_B_ked_N": [float(np.sqrt(np.mean(pb_k[:, i] ** 2))) for i in range(3)],
            "rms_P_C_ked_N": [float(np.sqrt(np.mean(pc_k[:, i] ** 2))) for i in range(3)],
        }
    result["max_abs_w_mid_coupled_m"] = float(np.max(np.abs(w_c)))
    return result


def main(argv=None):
    """Command line entry point."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--modes", type=int, default=3)
    parser.add_argument(
        "--reference",
        default=os.path.join(HERE, "..", "tests", "data", "paper_f20_state_t0.2.json"),
        help="reference modal state of the paper formulation at f = 20 Hz, t = 0.2 s",
    )
    parser.add_argument("--data", default=os.path.join(HERE, "data"))
    args = parser.parse_args(argv)

    report = {}
    if os.path.exists(args.reference):
        rel_eta, rel_deta = check_reference_state(args.reference, 3)
        print(f"reference state check (paper, f=20, r=3): rel err eta {rel_eta:.3e}, eta' {rel_deta:.3e}")
        report["reference_state_check"] = {
            "file": "tests/data/paper_f20_state_t0.2.json",
            "rel_error_eta": rel_eta,
            "rel_error_eta_dot": rel_deta,
        }
    else:
        sys.exit(f"reference state {args.reference} not found (pass --reference PATH)")
    for freq in (10.0, 20.0):
        res = compare(freq, args.modes, args.data)
        report[f"f{int(freq)}"] = res
        print(
            f"f = {freq:4.0f} Hz: rel L2 error of mid-point deflection, paper "
            f"{100 * res['paper']['rel_L2_w_mid_all_links']:.1f} %, consistent "
            f"{100 * res['consistent']['rel_L2_w_mid_all_links']:.1f} %"
        )
    report["definition"] = (
        "||w_ked - w_coupled|| / ||w_coupled||, 2-norm over all samples (every 2.5e-4 s, "
        "0-0.2 s) and all three links; w = mid-point deflection along the chord normal"
    )
    out = os.path.join(args.data, f"ked_vs_coupled{'' if args.modes == 3 else f'_r{args.modes}'}.json")
    with open(out, "w") as fh:
        json.dump(report, fh, indent=1)
    print(f"wrote {os.path.relpath(out, HERE)}")


if __name__ == "__main__":
    main()

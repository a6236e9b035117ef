"""Vectorised kinematics against the scalar calls, the CLI's kinematics table and closure."""

import csv
import subprocess

import numpy as np
import pytest

import flexprr


def circle_poses(t):
    """The paper's circle (docs/model.md): x = 0.05 cos(2 pi f t) - 0.05, y = 0.05 sin(2 pi f t), phi = 45 deg."""
    w = 2 * np.pi * 20.0
    return np.column_stack([0.05 * np.cos(w * t) - 0.05, 0.05 * np.sin(w * t), np.full_like(t, np.pi / 4)])


def test_vectorised_ik_equals_scalar_ik():
    poses = circle_poses(np.linspace(0.0, 0.05, 37))
    many = flexprr.inverse_kinematics(poses)
    assert many["rho"].shape == (37, 3) and many["beta"].shape == (37, 3)
    for i, p in enumerate(poses):
        one = flexprr.inverse_kinematics(p)
        assert one["rho"].shape == (3,)
        np.testing.assert_array_equal(one["rho"], many["rho"][i])
        np.testing.assert_array_equal(one["beta"], many["beta"][i])
    # lists are accepted as well as arrays
    np.testing.assert_array_equal(flexprr.inverse_kinematics(poses.tolist())["rho"], many["rho"])


def test_ik_equals_the_cli_kinematics_table(root, cli, tmp_path):
    out = tmp_path / "k.csv"
    subprocess.run([str(cli), "kinematics", str(root / "configs" / "paper_f20.toml"), "--out", str(out)], check=True)
    with open(out, newline="") as f:
        rows = list(csv.reader(f))
    header, data = rows[0], np.array([[float(v) for v in r] for r in rows[1:]])
    poses = data[:, [header.index("x_m"), header.index("y_m"), header.index("phi_rad")]]
    scene = flexprr.Scene.load(root / "configs" / "paper_f20.toml")
    ik = flexprr.inverse_kinematics(poses, scene=scene)
    # The CSV holds 11 significant digits (docs/scenes.md): the poses read back are rounded
    # by up to 5e-12 m, which moves a slider by as much, even where rho itself is near 0.
    for i in range(3):
        np.testing.assert_allclose(ik["rho"][:, i], data[:, header.index(f"rho_{i + 1}_m")], rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(ik["beta"][:, i], data[:, header.index(f"beta_{i + 1}_rad")], rtol=1e-10, atol=1e-10)


def test_forward_inverts_inverse():
    poses = circle_poses(np.linspace(0.0, 0.05, 11))
    rho = flexprr.inverse_kinematics(poses)["rho"]
    back = flexprr.forward_kinematics(rho, guess=poses + 1e-3)
    np.testing.assert_allclose(back, poses, atol=1e-10)
    one = flexprr.forward_kinematics(rho[3], guess=poses[3] + 1e-3)
    np.testing.assert_allclose(one, poses[3], atol=1e-10)


def test_singularity_measures_are_in_range_and_type_i_is_cos():
    poses = circle_poses(np.linspace(0.0, 0.05, 9))
    s = flexprr.singularity(poses)
    assert s["type_i"].shape == (9, 3) and s["type_ii"].shape == (9,)
    assert np.all((s["type_i"] >= 0) & (s["type_i"] <= 1)) and np.all((s["type_ii"] > 0) & (s["type_ii"] <= 1))
    # type I is |cos(beta_i - alpha_i)| with the paper's guide angles 150, 270, 30 degrees
    beta = flexprr.inverse_kinematics(poses)["beta"]
    alpha = np.radians([150.0, 270.0, 30.0])
    np.testing.assert_allclose(s["type_i"], np.abs(np.cos(beta - alpha)), atol=1e-12)


def test_unreachable_pose_raises_with_its_index():
    poses = circle_poses(np.linspace(0.0, 0.05, 5))
    poses[3] = [5.0, 5.0, 0.0]
    with pytest.raises(flexprr.KinematicsError) as info:
        flexprr.inverse_kinematics(poses)
    assert info.value.index == 3


def test_bad_shape_is_a_value_error():
    with pytest.raises(ValueError, match=r"\(n, 3\)"):
        flexprr.inverse_kinematics(np.zeros((4, 2)))


def scattered_poses():
    """Poses across the paper's workspace, away from singularities: a grid of centres within
    6 cm of the home position and orientations from 20 to 70 degrees."""
    xs, ys, phis = np.meshgrid(np.linspace(-0.06, 0.04, 4), np.linspace(-0.05, 0.05, 3), np.radians([20.0, 45.0, 70.0]))
    poses = np.column_stack([xs.ravel(), ys.ravel(), phis.ravel()])
    keep = []
    for p in poses:
        try:
            flexprr.inverse_kinematics(p)
        except flexprr.KinematicsError:
            continue
        keep.append(p)
    return np.array(keep)


def test_forward_kinematics_without_a_guess_inverts_the_inverse():
    """pose -> rho -> forward_kinematics(rho) -> pose with no guess: one row at a time from
    the nominal pose, and as a path by continuation from the previous row."""
    poses = scattered_poses()
    assert len(poses) >= 20
    for p in poses:
        back = flexprr.forward_kinematics(flexprr.inverse_kinematics(p)["rho"])
        np.testing.assert_allclose(back, p, atol=1e-10)
    path = circle_poses(np.linspace(0.0, 0.05, 101))
    np.testing.assert_allclose(flexprr.forward_kinematics(flexprr.inverse_kinematics(path)["rho"]), path, atol=1e-10)


def test_forward_kinematics_uses_the_scenes_nominal_pose(root):
    """A scene whose motion starts far from the paper's start: its own start is the guess."""
    scene = flexprr.Scene.load(root / "configs" / "pick_and_place.toml")
    start = scene["trajectory.from"]
    pose = np.array([start[0], start[1], np.radians(start[2])])
    rho = flexprr.inverse_kinematics(pose, scene=scene)["rho"]
    np.testing.assert_allclose(flexprr.forward_kinematics(rho, scene=scene), pose, atol=1e-10)

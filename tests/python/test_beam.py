"""Link frequencies against the closed form of a pinned-pinned Euler-Bernoulli beam."""

import numpy as np
import pytest

import flexprr

E, RHO, T, H, L = 7.3e10, 2770.0, 0.002, 0.03, 0.2
LINK = {
    "length": L,
    "modes": 3,
    "material": {"youngs_modulus": E, "density": RHO},
    "section": {"kind": "uniform", "thickness": T, "height": H},
    "basis": {"kind": "sine"},
}


def closed_form_omega2(p):
    """omega_n^2 = (n pi / l)^4 EI / rhoA + (n pi / l)^2 P / rhoA (sine modes are exact for constant P)."""
    ei, rho_a = E * H * T**3 / 12, RHO * T * H
    k = np.arange(1, 4) * np.pi / L
    return k**4 * ei / rho_a + k**2 * p / rho_a


@pytest.mark.parametrize("p0", [0.0, 50.0, -100.0])
def test_frequencies_equal_the_closed_form(p0):
    r = flexprr.link_frequencies(LINK, load=(p0, 0.0, 0.0))
    np.testing.assert_allclose(r["omega_squared"], closed_form_omega2(p0), rtol=1e-9)
    np.testing.assert_allclose(r["frequencies_hz"], np.sqrt(closed_form_omega2(p0)) / (2 * np.pi), rtol=1e-9)
    assert r["buckled"] is False
    assert r["total_mass"] == pytest.approx(RHO * T * H * L, rel=1e-12)


def test_file_and_dict_agree(root):
    from_file = flexprr.link_frequencies(root / "configs" / "link_paper.toml")
    from_dict = flexprr.link_frequencies(LINK, load=(50.0, 0.0, 0.0))
    np.testing.assert_array_equal(from_file["frequencies_hz"], from_dict["frequencies_hz"])


def test_euler_load_buckles():
    p_euler = np.pi**2 * E * H * T**3 / 12 / L**2
    r = flexprr.link_frequencies(LINK, load=(-1.01 * p_euler, 0.0, 0.0))
    assert r["buckled"] is True
    assert r["critical_load_factor"] == pytest.approx(1 / 1.01, rel=1e-9)


def test_unknown_key_is_a_scene_error():
    with pytest.raises(flexprr.SceneError) as info:
        flexprr.link_frequencies({**LINK, "lenght": 1.0})
    assert "lenght" in str(info.value)

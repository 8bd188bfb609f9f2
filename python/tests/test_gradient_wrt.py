"""Gradients with respect to physical parameters (``gradient(scene, wrt=[...])``) against central
differences of the objective, and the θ layout that ``gradient``/``optimize`` return passed back
as ``controls=``.

Reference numbers: the objective J itself, evaluated by ``gradient`` at p ± ε (a forward
simulation of the library, through ``Scene.replace``), differenced centrally with ε = 1e-4·|p|.
The truncation error of a central difference is O(ε²)·J''' relative, far below the 1e-6 the
adjoint's derivative is required to match."""

from __future__ import annotations

import numpy as np
import pytest

import chainbeam as cb

from conftest import SCENES


def riser() -> cb.Scene:
    """mpc_riser.toml (a 10-pendulum riser in a linear current, a harmonic point load, the
    objective Σ M₀²) for 2 s, with a top tension of 50 N so that every parameter below acts."""
    s = cb.Scene.from_file(SCENES / "mpc_riser.toml")
    return s.replace({"time.steps": 200, "loads.tension": 50.0, "control.values": [0.3]})


def central(scene: cb.Scene, key: str, rel: float = 1e-4) -> float:
    p = float(scene[key])
    eps = rel * abs(p)
    hi, _ = cb.gradient(scene.replace({key: p + eps}))
    lo, _ = cb.gradient(scene.replace({key: p - eps}))
    return (hi - lo) / (2.0 * eps)


@pytest.mark.parametrize(
    "key",
    ["loads.tension", "loads.drag", "loads.current.speed", "loads.point[0].harmonic[0].amplitude"],
)
def test_parameter_gradient_matches_central_differences(key: str) -> None:
    scene = riser()
    c, grads = cb.gradient(scene, wrt=[key])
    c0, _ = cb.gradient(scene)
    assert c == c0, "the objective does not depend on what is differentiated"
    fd = central(scene, key)
    assert grads[key] != 0.0
    assert abs(grads[key] - fd) <= 1e-6 * abs(fd), (key, grads[key], fd)


def test_wrt_keeps_order_and_controls_layout() -> None:
    scene = riser()
    c, g = cb.gradient(scene)
    c2, d = cb.gradient(scene, wrt=["loads.drag", "controls", "loads.tension"])
    assert list(d) == ["loads.drag", "controls", "loads.tension"]
    assert c2 == c
    np.testing.assert_array_equal(d["controls"], g)
    _, one = cb.gradient(scene, wrt="loads.tension")
    assert one["loads.tension"] == d["loads.tension"]


def test_wrt_errors_name_the_parameter() -> None:
    scene = riser()
    with pytest.raises(cb.InvalidArgumentError) as e:
        cb.gradient(scene, wrt=["loads.tensoin"])
    assert e.value.key == "wrt" and "loads.tensoin" in str(e.value)
    # A parameter the scene does not have: riser_5.toml has no tension.
    with pytest.raises(cb.InvalidArgumentError) as e:
        cb.gradient(cb.Scene.from_file(SCENES / "riser_5.toml"), wrt=["loads.tension"])
    assert e.value.kind == "NoSuchParameter"


def test_piecewise_theta_round_trips_as_controls() -> None:
    """θ of a piecewise control (P pieces, not 1 or N + 1 values) goes back in as is."""
    scene = riser().replace({"control.kind": "piecewise", "control.values": [0.2, -0.1, 0.4, 0.0]})
    c, g = cb.gradient(scene)
    assert g.shape == (4,)
    theta = np.array(scene["control.values"])
    c2, g2 = cb.gradient(scene, controls=theta)
    assert c2 == c
    np.testing.assert_array_equal(g2, g)
    np.testing.assert_array_equal(
        cb.simulate(scene, controls=theta).moment, cb.simulate(scene).moment
    )
    best = cb.optimize(scene, bound=5.0, max_iters=5, check=False)
    assert best.controls.shape == (4,)
    moved = scene.replace({"control.values": best.controls.tolist()})
    np.testing.assert_array_equal(
        cb.simulate(scene, controls=best.controls).moment, cb.simulate(moved).moment
    )
    with pytest.raises(cb.InvalidArgumentError) as e:
        cb.simulate(scene, controls=[1.0, 2.0, 3.0])
    assert "4 values" in str(e.value)

"""Recording.placed_poses / fitted_poses: where a bake places a blade of independent points,
which have no pose of their own (pure numpy, the add-on bakes with it)."""

import numpy as np
import pytest
from hapticut.recording import _rotate, fitted_poses


def quaternion_about_z(angle: float) -> np.ndarray:
    return np.array([np.cos(angle / 2), 0.0, 0.0, np.sin(angle / 2)])


def placed(poses: np.ndarray, local: np.ndarray) -> np.ndarray:
    """(K, N, 3): the blade's local points at the poses."""
    k, n = len(poses), len(local)
    rotations = np.repeat(poses[:, 3:], n, axis=0)
    points = _rotate(rotations, np.tile(local, (k, 1))).reshape(k, n, 3)
    return points + poses[:, None, :3]


LOCAL = np.stack([np.linspace(-20, 20, 5), np.zeros(5), np.full(5, 3.0)], axis=1)


def test_proxies_on_the_device_points_give_the_device_pose():
    device = np.array([[1.0, 2.0, 3.0, *quaternion_about_z(0.4)]])
    p = placed(device, LOCAL)
    assert np.allclose(fitted_poses(device, p, p), device)


def test_proxies_turned_across_the_edge_give_the_pose_turned_so():
    """Proxies where the device points would be after a turn about an axis across the edge
    (which the edge alone determines) and a move: the fitted pose is that turned pose."""
    device = np.array([[1.0, 2.0, 3.0, *quaternion_about_z(0.4)]] * 3)
    turned = device.copy()
    for k, angle in enumerate((0.3, -1.2, 2.9)):
        turned[k, 3:] = [np.cos((0.4 + angle) / 2), 0, 0, np.sin((0.4 + angle) / 2)]
        turned[k, :3] += (5.0 * k, -2.0, 1.0)
    fitted = fitted_poses(device, placed(device, LOCAL), placed(turned, LOCAL))
    assert np.allclose(fitted[:, :3], turned[:, :3])
    same_turn = np.abs(np.sum(fitted[:, 3:] * turned[:, 3:], axis=1))
    assert same_turn == pytest.approx(np.ones(3))


def test_an_edge_turned_end_over_end_or_collapsed_still_gives_a_pose():
    device = np.array([[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]] * 2)
    p = placed(device, LOCAL)
    reversed_q = p[:, ::-1].copy()
    collapsed = np.zeros_like(p)
    fitted = fitted_poses(device, p, np.concatenate([reversed_q[:1], collapsed[:1]]))
    assert np.all(np.isfinite(fitted))
    assert np.allclose(np.linalg.norm(fitted[:, 3:], axis=1), 1.0)
    # End over end: half a turn, so the device's first point lies on the last proxy.
    first = fitted[:1, :3] + _rotate(fitted[:1, 3:], LOCAL[:1])
    assert np.allclose(first, reversed_q[0, :1])
    # No edge to align: the device's rotation, moved onto the proxies' centre.
    assert np.allclose(fitted[1, 3:], device[1, 3:])

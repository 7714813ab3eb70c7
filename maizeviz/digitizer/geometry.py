"""Receiver orientation and motion compensation."""

from __future__ import annotations

import numpy as np


def euler_matrix(azimuth_deg: float, elevation_deg: float, roll_deg: float) -> np.ndarray:
    """Rotation (3, 3) of a receiver from the FASTRAK's Euler angles (degrees).

    Azimuth about z, then elevation about the new y, then roll about the new x
    (R = Rz(az) Ry(el) Rx(roll)): columns are the receiver's axes in the transmitter frame.
    """
    a, e, r = np.radians([azimuth_deg, elevation_deg, roll_deg])
    ca, sa, ce, se, cr, sr = np.cos(a), np.sin(a), np.cos(e), np.sin(e), np.cos(r), np.sin(r)
    rz = np.array([[ca, -sa, 0], [sa, ca, 0], [0, 0, 1]])
    ry = np.array([[ce, 0, se], [0, 1, 0], [-se, 0, ce]])
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    return rz @ ry @ rx


def to_reference_frame(point, ref_position, ref_angles) -> np.ndarray:
    """A stylus point (3,) re-expressed in the frame of a reference receiver at
    ``ref_position`` (3,) with Euler angles ``ref_angles`` (3,) deg: R^T (p - p_ref)."""
    rot = euler_matrix(*ref_angles)
    return rot.T @ (np.asarray(point, float) - np.asarray(ref_position, float))

"""A machine analysis as columns: the machine's table (machine.csv) and a group's (<group>.csv), SI, every
header naming its unit; shaft angles in degrees within [0, 360)."""
from __future__ import annotations

import numpy as np

from sewgen.machine import shaking


def angle_deg(phi) -> np.ndarray:
    """Shaft angles (rad) as degrees within [0, 360)."""
    return np.degrees(phi) % 360.0


def machine_table(a) -> dict:
    """Machine-level columns: bearing loads on the frame, torques, the shaking force and moments on the frame, the
    frame's force on the parts (sewgen.machine.shaking's convention), powers (SI; ``phi`` in deg)."""
    cols = {"phi [deg]": angle_deg(a.phi)}
    for which in ("front", "rear"):
        b = a.bearing(which)
        cols[f"bearing_{which}_on_frame.fx [N]"], cols[f"bearing_{which}_on_frame.fy [N]"] = b[:, 0], b[:, 1]
        cols[f"bearing_{which}_on_frame.magnitude [N]"] = np.hypot(b[:, 0], b[:, 1])
    cols["drive_torque [N*m]"] = a.torque
    for name, fa in a.groups.items():
        cols[f"{name}.torque [N*m]"] = fa.torque("shaft")
    if np.any(a.friction_power):  # columns only where the model switches friction on
        cols["bearings.friction_torque [N*m]"] = a.bearing_friction
        cols["friction_power [W]"] = a.friction_power
    sf = shaking.shaking_force_on_frame(a)  # inertia only; the weight on the frame is in summary.json
    cols["shaking_force_on_frame.fx [N]"], cols["shaking_force_on_frame.fy [N]"] = sf[:, 0], sf[:, 1]
    cols["shaking_force_on_frame.magnitude [N]"] = np.hypot(sf[:, 0], sf[:, 1])
    moments = shaking.shaking_moments_on_frame(a)
    for k, axis in enumerate("xyz"):
        cols[f"shaking_moments_on_frame.{axis} [N*m]"] = moments[:, k]
    fr = a.frame_force_on_parts
    cols["frame_force_on_parts.fx [N]"], cols["frame_force_on_parts.fy [N]"] = fr[:, 0], fr[:, 1]
    cols["drive_power [W]"] = a.drive_power
    cols["load_power [W]"] = a.load_power
    cols["energy_rate [W]"] = a.energy_rate()
    return cols


def group_table(fa, phi) -> dict:
    """Kinematics and forces of one group, one row per machine shaft angle ``phi`` (SI; angles of φ in deg)."""
    cols = {"phi [deg]": angle_deg(phi), "group_phi [deg]": angle_deg(fa.phi)}
    cols.update({k: v for k, v in fa.motion.table().items() if not k.startswith("phi ")})
    cols.update({k: v for k, v in fa.table().items() if not k.startswith("phi ")})
    return cols

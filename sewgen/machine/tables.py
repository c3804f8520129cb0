"""A machine analysis as columns: the machine's table (machine.csv) and a group's (<group>.csv), SI, every
header naming its unit; shaft angles in degrees within [0, 360)."""
from __future__ import annotations

import numpy as np

from sewgen.machine import shaking


def angle_deg(phi) -> np.ndarray:
    """Shaft angles (rad) as degrees within [0, 360)."""
    return np.degrees(phi) % 360.0


def machine_table(a) -> dict:
    """Machine-level columns: bearings, torques, shaking force and moment, powers (SI; ``phi`` in deg)."""
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
    sf = shaking.shaking_force(a)  # dynamic, on the frame; the weight apart (summary.json)
    cols["shaking_on_frame.fx [N]"], cols["shaking_on_frame.fy [N]"] = sf[:, 0], sf[:, 1]
    cols["shaking_on_frame.magnitude [N]"] = np.hypot(sf[:, 0], sf[:, 1])
    moments = shaking.shaking_moments(a)
    for k, axis in enumerate("xyz"):
        cols[f"shaking_on_frame.moment_{axis} [N*m]"] = moments[:, k]
    fr = a.frame_reaction
    cols["frame_on_parts.fx [N]"], cols["frame_on_parts.fy [N]"] = fr[:, 0], fr[:, 1]
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

"""Ideal tracked trajectories of Bennett linkages, made with `kinematics` (exact, noise-free)."""

import numpy as np

from kinematics import BennettLinkage


def ideal_record(linkage: BennettLinkage, driver_angles, points_per_link: int, rng, spread=0.04):
    """Positions {link: (frames, k, 3)} of k random points on each of links 1, 2, 3 as joint 3
    turns through ``driver_angles`` (rad, relative to home)."""
    t = linkage.parameter_from_joint(linkage.home_theta[3] + np.asarray(driver_angles), joint=3)
    poses = linkage.link_poses(t)
    scale = max(linkage.a)
    trajectories = {}
    for link in (1, 2, 3):
        # Points near the middle of the link (between its two axes at home), offset randomly.
        start = linkage.axes[link - 1].point
        end = linkage.axes[link % 4].point
        points = 0.5 * (start + end) + spread * scale * rng.normal(size=(points_per_link, 3))
        trajectories[link] = np.stack([poses[link].act(p) for p in points], axis=1)
    return trajectories


def write_vicon_csv(path, trajectories, rate=100.0, missing_frames=()):
    """A Vicon Nexus segment export (mm, degrees) of link origins; rotations are written as zeros."""
    names = {0: "Bennett:Link0", 1: "Bennett:Link1", 2: "Bennett:Link2", 3: "Bennett:Link3"}
    frames = next(iter(trajectories.values())).shape[0]
    lines = ["Segments", f"{rate:g}"]
    lines.append(",," + ",".join(f"{names[k]},,,,," for k in sorted(trajectories)))
    lines.append("Frame,Sub Frame," + ",".join("RX,RY,RZ,TX,TY,TZ" for _ in trajectories))
    lines.append(",," + ",".join("deg,deg,deg,mm,mm,mm" for _ in trajectories))
    for j in range(frames):
        cells = [str(j + 1), "0"]
        for k in sorted(trajectories):
            if j in missing_frames:
                cells += [""] * 6
            else:
                cells += ["0", "0", "0"] + [f"{1e3 * c:.9f}" for c in trajectories[k][j, 0]]
        lines.append(",".join(cells))
    path.write_text("\n".join(lines) + "\n")

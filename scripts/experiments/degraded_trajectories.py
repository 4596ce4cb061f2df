# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Copies of a folder of trajectory files, each spoilt the way another VIO or SLAM writes.

What the flow meets beyond the two trajectory sources at hand, from one of them (TUM
files, ``<recording>.txt``), one folder per kind under OUT:
- ``rate5``: every other pose (5 Hz from 10);
- ``keyframes``: a pose every 0.2-1.0 s at random (a SLAM's keyframe trajectory);
- ``noisy``: 0.5 deg of white rotation noise per axis and 2 cm of position per pose;
- ``jumps``: three relocalisations of 5 deg and 0.5 m that persist;
- ``lost``: two 8 s losses of tracking, each followed by a new world (a VIO's reset);
- ``short``: from 20 s after the first pose to 20 s before the last;
- ``init``: the first 5 s wrong by 8 deg per axis and pose (a VIO initialising);
- ``late``: every stamp 1.5 s late (a clock further off than the offset search);
- ``since_start``: stamps in time since the first pose (a clock the IMU's overlaps nowhere);
- ``inverted``: world-in-camera poses (T_cw, where TUM files hold T_wc);
- ``w_first``: the quaternions written qw qx qy qz.
Usage: .venv/bin/python scripts/experiments/degraded_trajectories.py SRC OUT [--seed N]
"""

import argparse
from pathlib import Path

from denoise_imu_ros.data.trajectory import read_tum, write_tum
import numpy as np
from scipy.spatial.transform import Rotation

LATE_NS = 1_500_000_000


def spoilt(stamp_ns: np.ndarray, pos: np.ndarray, quat: np.ndarray,
           rng: np.random.Generator) -> dict[str, tuple[np.ndarray, ...]]:
    """Return every kind's (stamp_ns, pos, quat) from one trajectory."""
    n, t = len(stamp_ns), (stamp_ns - stamp_ns[0]) * 1e-9
    rot = Rotation.from_quat(quat)
    kinds = {'rate5': (stamp_ns[::2], pos[::2], quat[::2])}
    keep, last, gap = [0], 0.0, rng.uniform(0.2, 1.0)
    for i in range(1, n):
        if t[i] - last >= gap:
            keep.append(i)
            last, gap = t[i], rng.uniform(0.2, 1.0)
    kinds['keyframes'] = (stamp_ns[keep], pos[keep], quat[keep])
    noise = Rotation.from_rotvec(rng.normal(0, np.radians(0.5), (n, 3)))
    kinds['noisy'] = (stamp_ns, pos + rng.normal(0, 0.02, (n, 3)), (rot * noise).as_quat())
    moved, where = rot, pos.copy()
    for j in sorted(rng.choice(np.arange(n // 5, 4 * n // 5), 3, replace=False)):
        turn = Rotation.from_rotvec(rng.normal(size=3) / np.sqrt(3) * np.radians(5))
        moved = Rotation.concatenate([moved[:j], turn * moved[j:]])
        where[j:] = turn.apply(where[j:]) + 0.5
    kinds['jumps'] = (stamp_ns, where, moved.as_quat())
    moved, where, tracked = rot, pos.copy(), np.ones(n, dtype=bool)
    for fraction in (0.35, 0.7):
        lost = t[int(fraction * n)]
        tracked &= (t < lost) | (t >= lost + 8.0)
        after = t >= lost + 8.0
        world = Rotation.from_rotvec(rng.normal(size=3) * 0.5)
        moved = Rotation.concatenate([moved[~after], world * moved[after]])
        where[after] = world.apply(where[after])
    kinds['lost'] = (stamp_ns[tracked], where[tracked], moved.as_quat()[tracked])
    inner = (t > 20.0) & (t < t[-1] - 20.0)
    kinds['short'] = (stamp_ns[inner], pos[inner], quat[inner])
    first = t < 5.0
    wrong = Rotation.from_rotvec(rng.normal(0, np.radians(8), (int(first.sum()), 3)))
    kinds['init'] = (stamp_ns, pos, Rotation.concatenate([wrong * rot[first],
                                                          rot[~first]]).as_quat())
    # written without random draws, so that the kinds above stay as they were drawn
    kinds['late'] = (stamp_ns + LATE_NS, pos, quat)
    kinds['since_start'] = (stamp_ns - stamp_ns[0], pos, quat)
    kinds['inverted'] = (stamp_ns, -rot.inv().apply(pos), rot.inv().as_quat())
    kinds['w_first'] = (stamp_ns, pos, quat[:, [3, 0, 1, 2]])
    return kinds


def main() -> None:
    """Write every kind of every trajectory in SRC under OUT/<kind>/."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    ap.add_argument('src', type=Path, help='folder of <recording>.txt (TUM)')
    ap.add_argument('out', type=Path)
    ap.add_argument('--seed', type=int, default=7)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    for path in sorted(args.src.glob('*.txt')):
        trajectory = read_tum(path)
        for kind, poses in spoilt(trajectory.stamp_ns, trajectory.pos, trajectory.quat,
                                  rng).items():
            (args.out / kind).mkdir(parents=True, exist_ok=True)
            write_tum(args.out / kind / path.name, *poses)
    print(f'written under {args.out}')


if __name__ == '__main__':
    main()

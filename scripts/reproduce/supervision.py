# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Whether smoothing or aligning the poses lets them supervise a correction, and transfer.

check-data's ``supervision`` fits one constant gyro bias on a recording's own
increments and asks whether removing it lowers the recording's attitude error. Here
the same test is run on the poses as recorded, moving-averaged over +-K pose samples
(no average across a hole), and moved onto the IMU clock and frame (``align: auto``);
then the bias fitted on the other recordings (256 samples) is applied to each one,
the most a constant correction learned elsewhere can do. AOE 3-D, degrees.
Usage: .venv/bin/python scripts/reproduce/supervision.py DATA_DIR NAME [NAME ...]
"""

import dataclasses
from pathlib import Path
import sys

from denoise_imu_ros.core.metrics import fit_constant_bias, sequence_errors
from denoise_imu_ros.core.records import Recording
from denoise_imu_ros.data.check import supervision
from denoise_imu_ros.data.load import load_recording, load_sequence
from denoise_imu_ros.data.timebase import onto_imu_stamps
import numpy as np
from scipy.spatial.transform import Rotation

LENGTHS = (16, 32, 256)
SMOOTHING = (3, 6, 12)  # +- pose samples


def smoothed(rec: Recording, k: int) -> Recording:
    """Poses averaged over +-k neighbours within k periods of time (holes not crossed)."""
    rot = Rotation.from_quat(rec.gt_quat)
    t = rec.gt_stamp_ns
    reach = (k + 0.5) * np.median(np.diff(t))
    out = np.empty_like(rec.gt_quat)
    for i in range(len(t)):
        lo, hi = max(0, i - k), min(len(t), i + k + 1)
        out[i] = rot[lo:hi][np.abs(t[lo:hi] - t[i]) <= reach].mean().as_quat()
    return dataclasses.replace(rec, gt_quat=out)


def row(label: str, report: dict) -> str:
    """One line: plain AOE, then after the bias fitted at each length."""
    return (f'  {label:24s} plain {report["aoe_plain_deg"]:5.2f}  ' + '  '.join(
        f'{j}: {f["aoe_deg"]:5.2f}' for j, f in report['fits'].items()))


def main(data: str, names: list[str]) -> None:
    """Print the table for each recording, then the transfer of the others' bias."""
    seqs = {}
    for name in names:
        rec = load_recording(Path(data) / name)
        print(name)
        print(row('as recorded', supervision(onto_imu_stamps(rec), LENGTHS)))
        for k in SMOOTHING:
            seq = onto_imu_stamps(smoothed(rec, k))
            print(row(f'moving average +-{k}', supervision(seq, LENGTHS)))
        seqs[name] = load_sequence(Path(data) / name, align_poses='auto')
        print(row('align: auto', supervision(seqs[name], LENGTHS)), flush=True)
    bias = {n: fit_constant_bias(s.gt_quat, s.gt_valid, s.imu[:, :3], s.dt, LENGTHS[-1])
            for n, s in seqs.items()}
    print(f'bias fitted on the other recordings ({LENGTHS[-1]} samples, align: auto)')
    for name, s in seqs.items():
        other = np.mean([b for n, b in bias.items() if n != name], axis=0)
        aoe = [sequence_errors(s, g, distances=())[1].aoe
               for g in (s.imu[:, :3], s.imu[:, :3] - other)]
        print(f'  {name}: plain {aoe[0]:.2f}, after {aoe[1]:.2f} (bias '
              + ', '.join(f'{v:+.4f}' for v in np.degrees(other)) + ' deg/s)')


if __name__ == '__main__':
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2:])

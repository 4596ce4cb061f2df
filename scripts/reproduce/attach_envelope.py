# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""Store the input envelope and its sustained bound in model files trained before they were."""

import argparse
from pathlib import Path
import sys

from denoise_imu_ros.core.errors import ModelFileError
from denoise_imu_ros.core.modelfile import add_metadata, read_model_file
from denoise_imu_ros.data.load import load_sequence
from denoise_imu_ros.learn.checkpoint import load_model
from denoise_imu_ros.learn.model import correct_gyro
from denoise_imu_ros.pipeline import envelope, stages


def _members_data(members: list[dict]) -> str | None:
    """Return the training folder an ensemble's first member names, if it is readable."""
    for member in members[:1]:
        try:
            return read_model_file(member['file']).meta.data
        except (KeyError, TypeError, ModelFileError):
            return None
    return None


def main() -> None:
    """Measure each file's envelope on its training spans, as training measures it."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument('models', nargs='+', help='model files, rewritten in place')
    parser.add_argument('--data', help="the training recordings' folder (default: the "
                        "file's own, as it was trained)")
    args = parser.parse_args()
    for path in args.models:
        loaded = load_model(path)
        meta = loaded.meta
        folder = args.data or meta.data or _members_data(meta.raw.get('members') or [])
        if folder is None:
            sys.exit(f'{path}: the file names no training folder: give --data')
        folder = Path(folder)
        imus, corrections, whole = [], [], []
        for name in meta.train_sequences:
            seq = load_sequence(folder / name, meta.recipe('imu_topic'),
                                meta.recipe('pose_topic'), meta.recipe('max_gt_gap_s'),
                                align_poses=meta.recipe('align', 'none'),
                                poses=meta.recipe('poses'))
            fed = seq.on_poses(stages.model_input(loaded, seq.stream))[:meta.training_span]
            imus.append(fed)
            whole.append(seq.imu)
            corrections.append(correct_gyro(loaded.model, fed) - fed[:, :3])
        # as training: the mean correction is the fallback where the turn-on bias is not
        # removed before the model
        bounds = envelope.measure(imus, None if meta.rest_bias else corrections,
                                  envelope.sustained_bound(whole, meta.sample_rate_hz))
        add_metadata(path, input_envelope=bounds.as_dict())
        print(f'{path}: gyro {bounds.gyro_rad_s:.3f} rad/s, accelerometer '
              f'{bounds.accel_offset_m_s2:.2f} m/s^2 off gravity ('
              f'{bounds.sustained_accel_m_s2:.2f} over a second), fallback '
              f'{[round(v, 5) for v in bounds.fallback_rad_s]} rad/s, over '
              f'{len(imus)} recordings')


if __name__ == '__main__':
    main()

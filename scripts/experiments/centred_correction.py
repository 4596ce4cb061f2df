# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Does a network trained on one power-on carry a constant into the next? An experiment.

After the turn-on bias is removed (``rest_bias``), what is left of a session's gyro error
in motion is partly a constant of that session (``check-data``'s bias against the poses
of the rest-debiased gyro: BROAD session B about +0.03 deg/s in x, session C about
-0.03 deg/s in z). A network learns its training session's constant and applies it to
the next. This removes the network's mean correction over its training recordings (what
a zero-mean network would output) and prints, per held-out recording, the open-loop AOE
of the raw gyro less its turn-on bias, of the network, and of the network so centred.
Usage: .venv/bin/python scripts/experiments/centred_correction.py MODEL DATA_DIR
       TRAIN_A,TRAIN_B,... HELD_A,HELD_B,...
"""

from pathlib import Path
import sys

from denoise_imu_ros.core.metrics import score
from denoise_imu_ros.data import rest_bias
from denoise_imu_ros.data.load import load_sequence
from denoise_imu_ros.learn.checkpoint import load_model
import numpy as np
import torch


def main(model: str, data: str, trained: list[str], held: list[str]) -> None:
    """Print the mean correction, then one line per held-out recording."""
    net = load_model(model)
    align = net.meta.recipe('align', 'none')

    def correction(imu: np.ndarray) -> np.ndarray:
        u = torch.as_tensor(rest_bias.model_input(net, imu), dtype=torch.float32)
        with torch.no_grad():
            return (net.model.gyro_std * net.model.correction(u[None]))[0].double().numpy()
    mean = np.concatenate([correction(load_sequence(Path(data) / n, align_poses=align).imu)
                           for n in trained]).mean(0)
    print('mean correction on the training recordings (mrad/s):', np.round(mean * 1e3, 3))
    settings = rest_bias.baseline_settings(net.meta)
    for name in held:
        seq = load_sequence(Path(data) / name, align_poses=align)
        gyro = net.correct(seq.imu)
        rest = rest_bias.remove_rest_bias(seq.imu, net.meta.sample_rate_hz, settings)
        figures = [score(seq, g)['aoe_deg'] for g in (rest[:, :3], gyro, gyro - mean)]
        print(f'{name}: rest bias {figures[0]:.2f}, network {figures[1]:.2f}, centred '
              f'{figures[2]:.2f} deg', flush=True)


if __name__ == '__main__':
    main(sys.argv[1], sys.argv[2], sys.argv[3].split(','), sys.argv[4].split(','))

# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The stillness detector's time constants, chosen on training recordings.

For each (rest_min_s, filter_tau_s) pair, the open-loop AOE of the raw gyro less its
causal turn-on bias estimate (``data/rest_bias.py``), per recording and averaged. A
shorter wait starts the estimate sooner, so less of the start is integrated with the
whole bias; too short a wait takes slow motion for stillness. The rest is VQF's defaults.
Usage: .venv/bin/python scripts/experiments/rest_detection.py DATA_DIR RECORDING...
"""

import dataclasses
import itertools
from pathlib import Path
import sys

from denoise_imu_ros.core.metrics import score
from denoise_imu_ros.data.load import load_sequence
from denoise_imu_ros.data.rest_bias import remove_rest_bias, RestBiasSettings
import numpy as np

WAITS_S = (0.25, 0.5, 1.0, 1.5)   # VQF's default: 1.5 s
TAUS_S = (0.1, 0.25, 0.5)         # VQF's default: 0.5 s


def main(data: str, names: list[str]) -> None:
    """Print one line per setting: the mean AOE and each recording's."""
    seqs = [load_sequence(Path(data) / n) for n in names]
    print(f'raw gyro: {np.mean([score(s, s.imu[:, :3])["aoe_deg"] for s in seqs]):.3f} deg')
    for wait, tau in itertools.product(WAITS_S, TAUS_S):
        if tau > wait:
            continue
        settings = dataclasses.replace(RestBiasSettings(), rest_min_s=wait, filter_tau_s=tau)
        errors = [score(s, remove_rest_bias(s.imu, s.rate_hz, settings)[:, :3])['aoe_deg']
                  for s in seqs]
        print(f'rest_min_s {wait:<5} filter_tau_s {tau:<5} mean {np.mean(errors):.3f} deg: '
              + ' '.join(f'{e:.2f}' for e in errors), flush=True)


if __name__ == '__main__':
    main(sys.argv[1], sys.argv[2:])

# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""Copy a crossval's fold models with the output bias tracking their fold was scored with."""

import json
from pathlib import Path
import shutil
import sys

from denoise_imu_ros.core.modelfile import add_metadata
from denoise_imu_ros.evaluation.crossval import CANDIDATES

USAGE = ('Usage: .venv/bin/python scripts/experiments/fold_tracking.py CROSSVAL_OUT DEST\n'
         'Writes DEST/fold<i>/<seed<s>|fold ensemble>/{network,calibrated}.safetensors '
         '(ensembles: CROSSVAL_OUT/fold<i>_ensemble.safetensors, if there), each with its '
         "fold's bias_tracking, for `denoise-imu eval` (fused rows, recordings outside the "
         'recipe).')


def main(out: Path, dest: Path) -> None:
    """Write the copies; the calibration beside each is seed 0's."""
    report = json.loads((out / 'crossval.json').read_text())
    for fold, choice in report['tracking']['per_fold'].items():
        sources = {f'seed{s}': out / f'seed{s}' / f'fold{fold}' / 'network.safetensors'
                   for s in report.get('seeds', [])}
        sources['ensemble'] = out / f'fold{fold}_ensemble.safetensors'
        for name, network in sources.items():
            if not network.is_file():
                continue
            folder = dest / f'fold{fold}' / name
            folder.mkdir(parents=True, exist_ok=True)
            shutil.copy(network, folder / 'network.safetensors')
            shutil.copy(out / 'seed0' / f'fold{fold}' / 'calibrated.safetensors',
                        folder / 'calibrated.safetensors')
            for row, file in (('network', 'network'), ('calibrated', 'calibrated')):
                settings = CANDIDATES[choice[row]]
                add_metadata(folder / f'{file}.safetensors',
                             bias_tracking=None if settings is None else settings.as_dict())
            print(f'{folder}: network {choice["network"]}, calibration {choice["calibrated"]}')


if __name__ == '__main__':
    if len(sys.argv) != 3:
        sys.exit(USAGE)
    main(Path(sys.argv[1]), Path(sys.argv[2]))

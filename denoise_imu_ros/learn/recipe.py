# Copyright 2026 denoise_imu_ros authors
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.
"""
A training recipe for your own recordings (``denoise-imu init-recipe``), from the data.

Every choice follows a documented rule from what ``check-data`` measures on each
recording; everything else is the reference recipe (``TrainConfig`` defaults):
- rate: the recordings' IMU rate (they must agree within the rate tolerance); the
  network, window and increments are in samples, so the model is for that rate only;
- increments: the paper's 0.08 and 0.16 s (16 and 32 samples at 200 Hz; in samples,
  the nearest powers of two: 8/16 at 100 Hz, 64/128 at 1 kHz) where they are not
  dominated by ground-truth noise on any recording, else the shortest clean length and
  its double;
- window: 80 s (the paper's), shortened to leave a third of the shortest recording as
  validation tail, in samples a multiple of the longest increment;
- sigma_g: per axis 1.2 times the largest constant gyro bias against the poses, at
  least 0.2 deg/s (the output scale the paper sets by hand: EuRoC [1, 2, 5], TUM-VI 0.2);
- align: ``auto`` when a recording's clock or frame is off (check-data), else ``none``.
Recordings whose poses cannot supervise even a constant bias (check-data's
``supervision``) are named in the reasons: such a recipe is not expected to beat plain
integration, whatever its other keys.
"""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from .config import TrainConfig
from ..core.atomic import write_text
from ..core.errors import DatasetError
from ..core.limits import common_rate
from ..data.check import check, paper_increments
from ..data.load import load_recording

WINDOW_S = 80.0
MIN_GYRO_STD_DEG = 0.2


def init_recipe(data: str | Path, sequences: list[str], imu_topic: str | None = None,
                pose_topic: str | None = None) -> tuple[dict[str, Any], list[str]]:
    """Return the recipe (a mapping of TrainConfig keys) and the reasons for each choice."""
    reports = {}
    for name in sequences:
        report = check(load_recording(Path(data) / name, imu_topic, pose_topic))
        if report['usable'] == 'no':
            raise DatasetError(f'{Path(data) / name}: not usable for training: '
                               + '; '.join(report['reasons']))
        reports[name] = report
    rate = common_rate({n: r['imu_rate_hz'] for n, r in reports.items()}, data)
    noisy = set().union(*(r['noise_dominated_increments'] for r in reports.values()))
    paper = paper_increments(rate)
    if not set(paper) & noisy:
        increments = list(paper)
        why_inc = "the paper's 0.08/0.16 s, clean on every recording"
    else:
        clean = [r['shortest_clean_increment'] for r in reports.values()]
        if None in clean:
            raise DatasetError('no increment up to 512 samples is free of ground-truth noise '
                               'on every recording: the poses cannot supervise the loss')
        first = max(clean)
        increments = [first, 2 * first]
        why_inc = (f"the paper's {paper[0]}/{paper[1]} are noise-dominated "
                   f'({sorted(noisy)}); {first} is clean on every recording')
    span = increments[-1]
    shortest = min(r['duration_s'] for r in reports.values()) * rate
    window = int(min(WINDOW_S * rate, shortest * 2 / 3) // span * span)
    if window < span:
        raise DatasetError(f'the shortest recording ({shortest / rate:.0f} s) leaves no '
                           f'training window of {span} samples')
    bias = np.max(np.abs([r['gyro_bias_vs_pose_deg_s'] for r in reports.values()]), axis=0)
    gyro_std = [max(MIN_GYRO_STD_DEG, round(1.2 * float(b), 2)) for b in bias]
    off = [n for n, r in reports.items() if r['usable'] == 'after alignment']
    recipe = {k: v for k, v in asdict(TrainConfig()).items() if k != 'device'}
    recipe.update(
        dataset=Path(data).name, data=str(data), sequences=list(sequences),
        imu_topic=imu_topic, pose_topic=pose_topic, increments=increments,
        increment_weights=[1.0, 0.5], window=window, gyro_std_deg=gyro_std,
        align='auto' if off else 'none', swa_start=1200, select='swa',
        workers=min(2, len(sequences)))
    why = [f'IMU rate {rate:.1f} Hz (the model is for this rate only; receptive field '
           f'511 samples = {511 / rate:.2f} s)',
           f'increments {increments} samples '
           f'({", ".join(f"{j / rate:.2f} s" for j in increments)}): ' + why_inc,
           f'window {window} samples ({window / rate:.0f} s)',
           f'gyro_std_deg {gyro_std}: 1.2 x the largest gyro bias per axis '
           f'({", ".join(f"{b:.3f}" for b in bias)} deg/s), at least {MIN_GYRO_STD_DEG}',
           f'align {recipe["align"]}' + (f': {", ".join(off)} off in clock or frame'
                                         if off else ': clocks and frames agree')]
    weak = [n for n, r in reports.items() if not r['supervision']['helps']]
    why.append(f'supervision: the poses of {", ".join(weak)} do not lower their own '
               'attitude error even with a constant bias fitted on them (check-data): a '
               'network trained on them is not expected to beat plain integration; run '
               'denoise-imu crossval before deploying it' if weak else
               "supervision: a constant bias fitted on each recording's poses lowers its "
               'attitude error')
    if len(sequences) < 2:
        why.append('one recording: train works, crossval (whether the network beats plain '
                   'integration on a recording it never saw) needs at least two')
    return recipe, why


def write_recipe(path: str | Path, recipe: dict[str, Any], why: list[str]) -> None:
    """Write the recipe as YAML, its reasons as comments on top."""
    text = ('# Written by denoise-imu init-recipe; see denoise_imu_ros/learn/config.py for '
            'every key.\n' + ''.join(f'# {line}\n' for line in why)
            + yaml.safe_dump(recipe, sort_keys=False))
    write_text(path, text)

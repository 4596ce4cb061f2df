# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
``denoise-imu correct``: a recording's IMU samples as imu/corrected carries them, in CSV.

Two engines give the same numbers (within 1e-6 rad/s): ``streaming``, the per-sample
numpy engine the node runs (no torch), and ``batch``, the torch network over the whole
recording (torch imported only then).
"""

from __future__ import annotations


import numpy as np

from ..core.atomic import atomic_output
from ..core.compat import check_stream
from ..core.errors import DatasetError
from ..core.modelfile import ModelFile, read_model_file, sample_rate
from ..data.load import load_imu
from ..pipeline import stages


def corrected_gyro(mf: ModelFile, imu: np.ndarray, engine: str = 'batch',
                   rest: str = 'model', guard: str = 'model', mix: str = 'model'
                   ) -> np.ndarray:
    """
    Corrected gyro (N, 3) rad/s of raw samples (N, 6) by either engine.

    ``rest`` (``model``, ``on``, ``off``): whether the turn-on bias is removed from the
    gyro first and the output's bias tracked, as the node's ``rest_bias`` parameter;
    ``guard`` and ``mix`` (``model``, ``off``) as its ``envelope_guard`` and
    ``classical_blend``.
    """
    if engine == 'streaming':
        return stages.corrected(mf, imu, rest, guard, mix=mix)
    from ..learn.checkpoint import load_model  # torch: the batch engine only
    from ..learn.model import correct_gyro
    net = load_model(mf.path).model
    return stages.corrected(mf, imu, rest, guard, lambda fed: correct_gyro(net, fed), mix)


def correct_to_csv(model_spec: str, source: str, output: str,
                   imu_topic: str | None = None, engine: str = 'batch',
                   rest: str = 'model', guard: str = 'model', mix: str = 'model',
                   accel_bias: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> int:
    """
    Write ``timestamp_ns,wx,wy,wz,ax,ay,az`` for every IMU sample of an ASL folder or bag.

    The columns of an ASL imu0/data.csv: the corrected gyro and the accelerometer less
    ``accel_bias``, as imu/corrected carries them. ``engine`` is ``batch`` (the torch
    network over the recording) or ``streaming`` (the per-sample numpy engine the online
    node uses); their outputs agree within 1e-6 rad/s.
    """
    loaded = read_model_file(model_spec)
    rec = load_imu(source, imu_topic)
    field = loaded.config.receptive_field
    if len(rec.imu) < field:
        raise DatasetError(f'{source}: {len(rec.imu)} IMU samples, shorter than the '
                           f'receptive field ({field})')
    check_stream(rec.imu_stamp_ns, rec.imu, source, sample_rate(loaded),
                 loaded.arrays['input_std'], loaded.arrays['input_mean'])
    omega = corrected_gyro(loaded, rec.imu, engine, rest, guard, mix)
    with atomic_output(output, overwrite=True) as tmp, open(tmp, 'w') as f:
        f.write('timestamp_ns,wx,wy,wz,ax,ay,az\n')
        for t, w, a in zip(rec.imu_stamp_ns, omega, rec.imu[:, 3:] - np.array(accel_bias)):
            f.write(f'{t},{w[0]:.9g},{w[1]:.9g},{w[2]:.9g},{a[0]:.9g},{a[1]:.9g},{a[2]:.9g}\n')
    return len(omega)

# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""Models and what they are used with: one check per pairing, on numpy and torch models alike."""

from denoise_imu_ros.core.compat import check_baseline, check_stream
from denoise_imu_ros.core.errors import DatasetError, ModelFileError
from denoise_imu_ros.core.modelfile import read_model_file, sample_rate
from denoise_imu_ros.data.load import load_imu
from denoise_imu_ros.pipeline.rest_bias import write_rest_only_model
from helpers import SAMPLE
import pytest


def test_a_calibration_of_the_models_rate_pairs_and_nothing_else_does(tmp_path):
    net, calib = read_model_file('euroc'), read_model_file('euroc_calibrated')
    check_baseline(net, calib)
    with pytest.raises(ModelFileError, match='euroc.safetensors: a network, not a calibration'):
        check_baseline(calib, net)
    with pytest.raises(ModelFileError, match='a calibration of 199.37 Hz, the model '
                                             'euroc.safetensors is of 200.00 Hz'):
        check_baseline(net, read_model_file('tumvi_calibrated'))
    write_rest_only_model(read_model_file('broad_network'), tmp_path / 'rest')
    with pytest.raises(ModelFileError, match='a rest-only model, not a calibration'):
        check_baseline(read_model_file('broad_network'), read_model_file(tmp_path / 'rest'))


def test_a_recording_is_checked_against_the_models_rate_units_and_mounting():
    rec, model = load_imu(SAMPLE), read_model_file('euroc')
    stats = model.arrays['input_std'], model.arrays['input_mean']
    check_stream(rec.imu_stamp_ns, rec.imu, 'sample', sample_rate(model), *stats)
    with pytest.raises(DatasetError, match='sample: IMU rate 200.0 Hz, the model was trained '
                                           'at 120.0 Hz'):
        check_stream(rec.imu_stamp_ns, rec.imu, 'sample', 120.0, *stats)
    deg = rec.imu.copy()
    deg[:, :3] *= 57.3
    with pytest.raises(DatasetError, match=r'gyro in deg/s\?'):
        check_stream(rec.imu_stamp_ns, deg, 'sample', sample_rate(model), *stats)

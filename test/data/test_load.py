# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""Reading a recording: ASL folder or bag by its path, a clear error for what is not there."""

from denoise_imu_ros.core.errors import DatasetError
from denoise_imu_ros.data.load import is_bag, load_imu, load_sequence
from helpers import write_asl
import pytest


def test_a_bag_is_told_by_its_suffix_or_its_metadata(tmp_path):
    assert is_bag('run.mcap') and is_bag('run.db3') and is_bag('run.bag')
    assert not is_bag(tmp_path)
    (tmp_path / 'metadata.yaml').write_text('rosbag2_bagfile_information: {}\n')
    assert is_bag(tmp_path)


def test_a_missing_recording_names_the_bag_of_that_name_beside_it(tmp_path):
    (tmp_path / 'MH_01.mcap').write_bytes(b'')
    with pytest.raises(DatasetError, match=r'MH_01: no such sequence folder or bag \(there '
                                           r'is MH_01.mcap: name it with its suffix\)'):
        load_imu(tmp_path / 'MH_01')


def test_a_recording_at_another_rate_than_the_models_is_refused_before_any_figure(tmp_path):
    write_asl(tmp_path / 'rec', n_imu=800, imu_rate=100.0, gt_rate=100.0)
    seq = load_sequence(tmp_path / 'rec', rate_hz=100.0)
    assert len(seq.imu) == 800
    with pytest.raises(DatasetError, match='IMU rate 100.0 Hz, the model was trained at 200.0'):
        load_sequence(tmp_path / 'rec', rate_hz=200.0)

# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""Atomic outputs: complete under their name, or nothing at all."""

from denoise_imu_ros.core.atomic import atomic_output, write_text
from denoise_imu_ros.core.errors import OutputError
import pytest


def test_the_output_appears_only_when_complete_and_no_scratch_is_left(tmp_path):
    out = tmp_path / 'sub' / 'report.csv'
    with atomic_output(out) as tmp:
        tmp.write_text('a,b\n')
        assert not out.exists()  # written elsewhere until done
    assert out.read_text() == 'a,b\n'
    assert [p.name for p in out.parent.iterdir()] == ['report.csv']


def test_a_failure_half_way_leaves_nothing_behind(tmp_path):
    out = tmp_path / 'bag'
    with pytest.raises(RuntimeError):
        with atomic_output(out) as tmp:
            tmp.mkdir()
            (tmp / 'bag_0.mcap').write_bytes(b'half')
            raise RuntimeError('the input ended early')
    assert list(tmp_path.iterdir()) == []


def test_an_existing_output_is_refused_unless_overwritten_and_never_a_folder(tmp_path):
    out = tmp_path / 'model.safetensors'
    out.write_text('old')
    with pytest.raises(OutputError, match='exists already'):
        with atomic_output(out):
            pass
    write_text(out, 'new')
    assert out.read_text() == 'new'
    (tmp_path / 'folder').mkdir()
    with pytest.raises(OutputError, match='a folder exists there'):
        with atomic_output(tmp_path / 'folder', overwrite=True):
            pass

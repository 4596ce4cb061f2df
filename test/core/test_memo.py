# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The caches of the last recordings read: their keys and what they forget."""

from denoise_imu_ros.core.memo import content_key, files_key, Kept
import numpy as np


def test_content_keys_tell_apart_stamps_a_float_cannot_and_arrays_of_other_shapes():
    stamps = 1_403_636_579_758_555_648 + np.arange(5, dtype=np.int64) * 5_000_000
    assert content_key(stamps) != content_key(stamps + 100)  # 256 ns apart as float64
    a = np.arange(6.0)
    assert content_key(a[:2], a[2:]) != content_key(a[:3], a[3:])
    assert content_key(a.reshape(2, 3)) != content_key(a.reshape(3, 2))
    assert content_key(a, salt='0.5') != content_key(a, salt='1')
    assert content_key(a.reshape(2, 3).T) == content_key(np.ascontiguousarray(a.reshape(2, 3).T))


def test_kept_values_are_forgotten_oldest_first_by_weight_and_none_is_never_kept():
    computed = []

    def compute(value):
        def make():
            computed.append(value)
            return value
        return make
    kept = Kept(5, weigh=len)
    assert kept.get('a', compute('aa')) == 'aa' and kept.get('a', compute('xx')) == 'aa'
    kept.get('b', compute('bbb'))
    kept.get('a', compute('xx'))  # 'a' is now the most recent: 'b' goes first
    kept.get('c', compute('c'))
    assert kept.get('b', compute('bbb')) == 'bbb' and computed == ['aa', 'bbb', 'c', 'bbb']
    kept.get('big', compute('bigger'))  # heavier than all: computed, not kept
    kept.get('big', compute('bigger'))
    kept.get(None, compute('n'))
    kept.get(None, compute('n'))
    assert computed[-4:] == ['bigger', 'bigger', 'n', 'n']


def test_a_file_written_anew_has_another_key_whatever_its_size_and_time(tmp_path):
    import os
    bag = tmp_path / 'bag'
    bag.mkdir()
    (bag / 'x.mcap').write_bytes(b'1234')
    before = files_key(bag)
    stat = (bag / 'x.mcap').stat()
    (bag / 'x.mcap').unlink()
    (bag / 'x.mcap').write_bytes(b'5678')
    os.utime(bag / 'x.mcap', ns=(stat.st_atime_ns, stat.st_mtime_ns))  # as `cp -p` would
    assert files_key(bag) != before and files_key(bag) == files_key(bag)
    assert files_key(tmp_path / 'nowhere') == ()

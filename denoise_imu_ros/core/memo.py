# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
What a process keeps of the last recordings it read: costly results, by their inputs' content.

``crossval``, ``eval`` and ``check-data`` read a recording once per fold, seed or check;
a bag's deserialisation, a pose alignment and a spline fit cost seconds where hashing
their inputs costs milliseconds. Keys are :func:`content_key` digests (every array's
type, shape and bytes) or, for files, :func:`files_key` (identity, size and times).
"""

from __future__ import annotations

from collections import OrderedDict
import hashlib
from pathlib import Path
from typing import Callable, Generic, Hashable, TypeVar

import numpy as np

__all__ = ['content_key', 'files_key', 'Kept']

_V = TypeVar('_V')


def content_key(*arrays: np.ndarray, salt: str = '') -> str:
    """Return a digest of some arrays (each one's dtype, shape and bytes) and a salt."""
    digest = hashlib.blake2b(salt.encode())
    for a in arrays:
        a = np.ascontiguousarray(a)
        digest.update(f'{a.dtype.str}{a.shape}'.encode())
        digest.update(a.tobytes())
    return digest.hexdigest()


def files_key(path: Path) -> tuple | None:
    """
    Return the files of a folder (or one file) with their inode, size and times; None if unread.

    The change time is set by the file system at every write (unlike the modification
    time, which a copy or ``touch`` may set): a file written anew has another key.
    """
    try:
        files = sorted(path.rglob('*')) if path.is_dir() else [path]
        stats = [(str(f.resolve()), f.stat()) for f in files if f.is_file()]
    except OSError:  # gone while listed
        return None
    return tuple((name, s.st_ino, s.st_size, s.st_mtime_ns, s.st_ctime_ns) for name, s in stats)


class Kept(Generic[_V]):
    """
    The values of the last keys asked for, the oldest forgotten first.

    At most ``size`` of them, or, with ``weigh``, values whose weights add up to ``size``
    at most (a value heavier than that alone is computed but not kept).
    """

    def __init__(self, size: int, weigh: Callable[[_V], int] = lambda value: 1) -> None:
        self.size, self.weigh = size, weigh
        self._values: OrderedDict[Hashable, tuple[_V, int]] = OrderedDict()
        self._total = 0

    def get(self, key: Hashable | None, compute: Callable[[], _V]) -> _V:
        """Return the value kept for ``key``, or compute it and keep it (None: never kept)."""
        if key in self._values:
            self._values.move_to_end(key)
            return self._values[key][0]
        value = compute()
        weight = self.weigh(value)
        if key is None or weight > self.size:
            return value
        self._values[key] = value, weight
        self._total += weight
        while self._total > self.size:
            self._total -= self._values.popitem(last=False)[1][1]
        return value

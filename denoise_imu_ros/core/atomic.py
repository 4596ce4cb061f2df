# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Atomic outputs: a file or bag appears complete under its name, or not at all.

A crash, a full disk or bad input half-way through must not leave a half-written bag
(which then blocks the retry: "exists already") or a truncated CSV or model file.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
import os
from pathlib import Path
import secrets
import shutil
from typing import Any

from .errors import OutputError


@contextmanager
def atomic_output(path: str | Path, overwrite: bool = False) -> Iterator[Path]:
    """
    Yield a temporary path to write ``path``'s content to; moved into place on success.

    The temporary path is in a hidden folder beside ``path`` (same file system, so the
    final rename is atomic) and has ``path``'s own name, so a bag's inner files are
    named as they would be. On any failure nothing is left behind.
    """
    path = Path(path)
    if path.exists() and overwrite and not path.is_file():  # never a folder's content
        raise OutputError(f'{path}: a folder exists there; --overwrite replaces a file, not '
                          'a folder: give another name, or remove it first')
    if path.exists() and not overwrite:
        raise OutputError(f'{path}: exists already')
    # named before it exists, so that a signal right after its creation still removes it
    scratch = path.parent / f'.{path.name}.{secrets.token_hex(4)}'
    try:
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            scratch.mkdir(mode=0o700)
        except OSError as err:
            if isinstance(err, FileExistsError):
                scratch = None  # another writer's: not ours to remove
            raise OutputError(f'{path}: cannot write here ({err.strerror})') from err
        yield scratch / path.name
        os.replace(scratch / path.name, path)
    except OSError as err:  # a full disk: name the output, not the scratch copy
        if err.filename and Path(err.filename).resolve() != (scratch / path.name).resolve():
            raise OutputError(f'{err.filename}: {err.strerror or err}') from err
        raise OutputError(f'{path}: cannot write ({err.strerror or err})') from err
    finally:
        if scratch is not None:
            shutil.rmtree(scratch, ignore_errors=True)


def write_text(path: str | Path, text: str) -> None:
    """Write a text file complete or not at all (a report beside earlier ones)."""
    with atomic_output(path, overwrite=True) as tmp:
        tmp.write_text(text)


def save_figure(fig: Any, path: str | Path) -> None:
    """Save a matplotlib figure complete or not at all (never a truncated PNG)."""
    with atomic_output(path, overwrite=True) as tmp:
        fig.savefig(tmp, dpi=90)

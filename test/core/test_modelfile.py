# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The code version a model file records: the commit only of the package's own checkout."""

import subprocess

from denoise_imu_ros import __version__
from denoise_imu_ros.core.modelfile import code_version


def _git(cwd, *args):
    return subprocess.run(['git', *args], cwd=cwd, check=True, capture_output=True,
                          text=True).stdout.strip()


def test_the_commit_is_recorded_only_where_git_tracks_the_package(tmp_path):
    repo = tmp_path / 'workspace'
    (repo / 'src' / 'pkg').mkdir(parents=True)
    (repo / 'install' / 'pkg').mkdir(parents=True)
    for folder in (repo / 'src' / 'pkg', repo / 'install' / 'pkg'):
        (folder / '__init__.py').write_text('')
    _git(repo, 'init', '-q')
    _git(repo, 'add', 'src')
    _git(repo, '-c', 'user.name=t', '-c', 'user.email=t@t', 'commit', '-qm', 'c')
    rev = _git(repo, 'rev-parse', '--short', 'HEAD')
    assert code_version(repo / 'src' / 'pkg') == f'{__version__}+g{rev}'
    # an installed copy inside the same repository: not this commit's code
    assert code_version(repo / 'install' / 'pkg') == __version__
    (repo / 'src' / 'pkg' / '__init__.py').write_text('x = 1\n')
    assert code_version(repo / 'src' / 'pkg') == f'{__version__}+g{rev}.dirty'
    assert code_version(tmp_path) == __version__  # no repository at all

# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The code version a model file records: a digest of the package's own sources, no git."""

import shutil

from denoise_imu_ros import __version__
from denoise_imu_ros.core.modelfile import code_version


def test_the_version_names_the_sources_wherever_they_are_installed(tmp_path):
    src, installed = tmp_path / 'src' / 'pkg', tmp_path / 'install' / 'pkg'
    (src / 'sub').mkdir(parents=True)
    (src / '__init__.py').write_text('')
    (src / 'sub' / 'mod.py').write_text('x = 1\n')
    shutil.copytree(src, installed)
    (installed / 'sub' / 'mod.pyc').write_bytes(b'compiled, not a source')
    version = code_version(src)
    assert version.startswith(f'{__version__}+src.') and version == code_version(installed)
    (src / 'sub' / 'mod.py').write_text('x = 2\n')  # one changed line: another version
    assert code_version(src) != version
    (src / 'sub' / 'mod.py').write_text('x = 1\n')
    (src / 'sub' / 'mod.py').rename(src / 'mod.py')  # the same text elsewhere: another code
    assert code_version(src) != version

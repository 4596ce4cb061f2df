# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""Every source file opens with its SPDX lines and what it is for; the licence they name."""

import ast
import subprocess

from helpers import ROOT
import pytest

HEADER = ['# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors',
          '# SPDX-License-Identifier: Apache-2.0']


def _sources():
    listed = subprocess.run(['git', 'ls-files', '*.py'], cwd=ROOT, capture_output=True,
                            text=True)
    if listed.returncode != 0:  # an exported tree: every Python file in it
        return sorted(p.relative_to(ROOT).as_posix() for p in ROOT.rglob('*.py')
                      if '.venv' not in p.parts and 'build' not in p.parts)
    return listed.stdout.split()


def test_every_source_file_opens_with_spdx_lines_and_a_one_line_purpose():
    wrong = []
    for name in _sources():
        text = (ROOT / name).read_text(encoding='utf-8')
        doc = ast.get_docstring(ast.parse(text)) if text.strip() else None
        if text.splitlines()[:2] != HEADER or not doc or not doc.splitlines()[0].strip():
            wrong.append(name)
    assert wrong == []


def test_the_licence_the_files_name_is_there():
    assert 'Apache License' in (ROOT / 'LICENSE').read_text()
    assert '<license>Apache-2.0</license>' in (ROOT / 'package.xml').read_text()


@pytest.mark.copyright
@pytest.mark.linter
def test_ament_copyright_where_installed():
    """The ROS linter, where installed (a real ROS install; not on PyPI)."""
    main = pytest.importorskip('ament_copyright.main').main
    assert main(argv=['.', 'test']) == 0, 'Found errors'

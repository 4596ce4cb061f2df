# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The reproduce scripts import, and their tables say what the figures say."""

import importlib.util
from pathlib import Path

import pytest

SCRIPTS = Path(__file__).resolve().parents[2] / 'scripts' / 'reproduce'


def _load(name: str):
    spec = importlib.util.spec_from_file_location(name, SCRIPTS / f'{name}.py')
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize('name', sorted(p.stem for p in SCRIPTS.glob('*.py')))
def test_every_reproduce_script_imports_and_has_a_main(name):
    """What docs/results.md cites runs: nothing it imports has moved or gone."""
    module = _load(name)
    assert callable(module.main) and module.__doc__.strip()


def _rows(net: float, tracker: float) -> dict:
    return {m: {'aoe_deg': v} for m, v in (('raw', 40.0), ('rest bias', 5.0),
                                           ('tracker only', tracker), ('calibrated', 3.0),
                                           ('network', net))}


def test_broad_folds_measures_the_network_against_the_classical_pipeline():
    folds = _load('broad_folds')
    recordings = {'a': _rows(1.0, 2.0), 'b': _rows(3.3, 3.0)}
    got = folds.ratios(recordings, ['a', 'b'], 'network')
    assert got['mean'] == pytest.approx(2.15) and got['bar'] == pytest.approx(2.5)
    assert got['ratio'] == pytest.approx(2.15 / 2.5)
    assert got['mean_ratio'] == pytest.approx((0.5 + 1.1) / 2)  # many small losses count
    assert got['worst_ratio'] == pytest.approx(1.1)
    report = {'seeds': [0], 'folds': [['a', 'b']], 'recordings': recordings,
              'mean': {m: {} for m in recordings['a']},
              'per_seed': {'0': {'recordings': recordings}}}
    lines = folds.open_loop(report)
    assert '| a | 40.00 | 5.00 | 2.00 | 3.00 | 1.00 | 1.00 |' in lines
    assert ('- ensemble, network: mean 2.15 against 2.50 (0.86x), mean per-trial ratio 0.80, '
            'worst 1.10') in lines

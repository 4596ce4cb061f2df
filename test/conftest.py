# Copyright 2026 denoise_imu_ros authors
# Licensed under the Apache License, Version 2.0
"""Shared fixtures: the real data beside the checkout, skipped cleanly when absent."""

from pathlib import Path

from denoise_imu_ros.model import GyroNet, ModelConfig
from denoise_imu_ros.modelfile import save_model
import pytest
import torch

DATA = Path(__file__).resolve().parents[1].parent / 'shared' / 'data'
SAMPLE = Path(__file__).resolve().parents[1] / 'denoise_imu_ros' / 'sample' / 'euroc_V1_03_90s'


def untrained_model(**config) -> GyroNet:
    """Build a seeded, untrained eval-mode network with EuRoC-like input normalisation."""
    torch.manual_seed(0)
    model = GyroNet(ModelConfig(**config))
    model.set_normalization(torch.tensor([0.0, 0.0, 0.0, 9.0, 0.0, -3.0]),
                            torch.tensor([0.3, 0.3, 0.3, 1.0, 1.0, 1.0]))
    return model.eval()


@pytest.fixture()
def model_file(tmp_path) -> Path:
    """Write an untrained but complete 200 Hz model file with residual std figures."""
    path = tmp_path / 'model.safetensors'
    save_model(path, untrained_model(), {
        'dataset': 'test', 'sample_rate_hz': 200.0,
        'validation': {'gyro_residual_std': [0.01, 0.02, 0.03]}})
    return path


@pytest.fixture(scope='session')
def data_dir() -> Path:
    """Return ../shared/data, or skip the test."""
    if not (DATA / 'euroc').is_dir():
        pytest.skip(f'real data not found at {DATA}')
    return DATA


@pytest.fixture(scope='session')
def euroc(data_dir: Path) -> Path:
    """Return the folder of the EuRoC ASL sequences."""
    return data_dir / 'euroc'

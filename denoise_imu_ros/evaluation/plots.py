# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Figures of ``eval`` and the live demo: errors a person reads at a glance.

No Euler angles of the attitude itself: near pitch +-90 deg (EuRoC's IMU frame on V1_03)
its roll and yaw swing by hundreds of degrees at every step of a wrap, artefacts, not
errors. Plotted instead are the error's angle, its tilt (what gravity can correct) and
its yaw about the world z axis, wrapped to +-180 deg and never joined across a wrap.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from ..core.atomic import save_figure
from ..core.metrics import error_components, ROE_DISTANCES_M
from ..core.records import Sequence


def _pyplot() -> Any:
    """Matplotlib without a display, imported only where a figure is drawn."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    return plt


def unjoined(t: np.ndarray, values: np.ndarray,
             jump: float = 180.0) -> tuple[np.ndarray, np.ndarray]:
    """Both arrays with NaN inserted where consecutive values jump by more than ``jump``."""
    values = np.asarray(values, dtype=float)
    cut = np.flatnonzero(np.abs(np.diff(values)) > jump) + 1
    return np.insert(np.asarray(t, dtype=float), cut, np.nan), np.insert(values, cut, np.nan)


def plot_errors(path: Path, title: str, t: np.ndarray, valid: np.ndarray,
                errors: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]) -> None:
    """
    Three panels against time: error angle and tilt error (log), yaw error (symlog, +-180).

    ``errors`` maps a label to its (angle, tilt, yaw) arrays in degrees; stamps without
    trusted ground truth are left out.
    """
    plt = _pyplot()
    fig, axes = plt.subplots(3, 1, figsize=(10, 8.5), sharex=True)
    for label, (angle, tilt, yaw) in errors.items():
        axes[0].plot(t, np.where(valid, angle, np.nan), lw=0.8, label=label)
        axes[1].plot(t, np.where(valid, tilt, np.nan), lw=0.8, label=label)
        yaw = np.where(valid, yaw, np.nan)
        axes[2].plot(*unjoined(t, yaw), lw=0.8, label=label)
    for ax, name in zip(axes, ('attitude error (deg)', 'tilt error (deg)',
                               'yaw error (deg)')):
        ax.set_ylabel(name)
        ax.grid(True, alpha=0.3)
    for ax in axes[:2]:
        ax.set_yscale('log')
        ax.set_ylim(0.01, 360)
    # symmetric log: a network's tenths of a degree and raw's wraps on one axis
    axes[2].set_yscale('symlog', linthresh=0.1)
    axes[2].set_ylim(-180, 180)
    axes[2].set_yticks([-180, -10, -1, -0.1, 0, 0.1, 1, 10, 180])
    axes[2].set_yticklabels(['-180', '-10', '-1', '-0.1', '0', '0.1', '1', '10', '180'])
    axes[2].set_xlabel('time (s)')
    axes[0].legend(loc='upper left', fontsize=8)
    axes[0].set_title(title)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


def plot_sequence(path: Path, seq: Sequence, estimates: dict[str, Rotation]) -> None:
    """Each method's attitude error against the ground truth of one sequence."""
    gt = Rotation.from_quat(seq.gt_quat)
    t = (seq.stamp_ns - seq.stamp_ns[0]) * 1e-9
    plot_errors(path, seq.name, t, seq.gt_valid,
                {m: error_components(r, gt) for m, r in estimates.items()})


def plot_roe(path: Path, roe_all: dict[str, list[dict[float, np.ndarray]]]) -> None:
    """Box plots of relative orientation error per distance travelled, one per method."""
    plt = _pyplot()
    fig, axes = plt.subplots(1, len(ROE_DISTANCES_M), figsize=(12, 4))
    for ax, d in zip(axes, ROE_DISTANCES_M):
        data = [np.concatenate([r[d] for r in runs]) for runs in roe_all.values()]
        ax.set_title(f'ROE over {d:g} m (deg)')
        if not all(len(x) and (x > 0).any() for x in data):
            ax.text(0.5, 0.5, f'never travelled {d:g} m', ha='center', va='center',
                    transform=ax.transAxes)
            ax.set_xticks([])
            continue
        ax.boxplot(data, showfliers=False)
        ax.set_xticks(range(1, len(data) + 1), list(roe_all), rotation=20)
        ax.set_yscale('log')
        ax.grid(True, alpha=0.3)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)

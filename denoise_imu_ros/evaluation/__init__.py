# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Scoring against ground truth: ``eval``, ``crossval``, ``correct``, their tables and plots.

``correct`` (with the streaming engine), ``reports`` and ``plots`` need no torch;
``evaluate`` and ``crossval`` run the batch network. Import the module you need: this
package imports none of them.
"""

__all__ = ['correct', 'crossval', 'evaluate', 'plots', 'reports']

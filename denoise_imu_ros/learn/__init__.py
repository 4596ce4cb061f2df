# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Training, with torch: the network, its loss, the training loop, recipes.

``config`` and ``recipe`` are torch-free (``init-recipe`` needs no torch); ``model``,
``checkpoint``, ``so3``, ``loss``, ``parallel`` and ``train`` import it. Import the
module you need: this package imports none of them.
"""

__all__ = ['checkpoint', 'config', 'loss', 'model', 'parallel', 'recipe', 'so3', 'train']

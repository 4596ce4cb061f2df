# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The correction pipeline, every stage per sample and over arrays: numpy and VQF only.

``stages`` is the one table: the order of the stages, what each does per sample and over
a recording, and the events that reset it; ``online`` checks each incoming sample and
drives that table (the node and process-bag); the offline tools run the same table over
arrays. The stages themselves: ``rest_bias`` (the turn-on bias before the model, the bias
tracked after it), ``streaming`` (the network, its step compiled from ``_step.c`` where
built), ``envelope`` (the model not trusted beyond the motion it was trained on),
``blend`` (the classical mix), ``vertical`` (a heading-less model's correction about the
vertical dropped),
``covariance`` (each output's variance) and ``fusion`` (the gravity-aided orientation).
Import the module you need: this package imports none of them.
"""

__all__ = ['blend', 'covariance', 'envelope', 'fusion', 'online', 'rest_bias', 'stages',
           'streaming', 'vertical']

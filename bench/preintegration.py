# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
What a VIO back-end gets from imu/corrected: its increments pre-integrated by GTSAM, beside ours.

For each recording and window length, the IMU as ``imu/corrected`` carries it (each model's
corrected gyro and its accelerometer less the bias the model fitted, ``fusion_accel_bias``,
unless its cross-validation found that bias does not carry to unseen recordings; beside it
the raw IMU and the accelerometer as it came, ``fusion_accel_bias:=off``) is
pre-integrated over back-to-back windows by
GTSAM's PreintegratedImuMeasurements (what GTSAM-based smoothers use; ``pip install
gtsam``) and by denoise_imu_ros.evaluation.preintegration, and compared with the ground
truth's increments (its velocity EuRoC's state estimate's where the recording has one, as
a VIO's evaluation takes it, else the derivative of its positions: EuRoC's positions jump by
up to 0.14 m in one sample, which a derivative turns into 28 m/s). Prints per row the RMS rotation
(deg), velocity (m/s) and position (m) increment errors, the mean NEES of rotation and
velocity with the covariance propagated from the per-sample covariance (what
``imu/corrected`` publishes: each message's own variances where the model file has them
(``fit-variance``), beside, for the gyro, its validation residual, one for every message
(the datasheet's where the file has none); the accelerometer's where the file has none and
the raw IMU's: EuRoC's sensor.yaml noise densities, as a VIO configuration takes them) and
the fraction of windows inside the 2-sigma ellipsoid (73.9 % if the covariance is right),
then the largest difference between GTSAM's increments and
ours (GTSAM integrates in the tangent space of the rotation with its exact Jacobians, where
ours takes one sample's right Jacobian as the identity: the two agree to the order of that
term, not to rounding, on EuRoC; on TUM-VI's handheld motion the increments differ by up to
0.04 and the covariances' rotation-velocity terms by up to 0.4 of the largest entry, which that
term does not explain: GTSAM's NEES are the ones printed).
Run: .venv/bin/python bench/preintegration.py [--data ../shared/data/euroc]
[--sequences MH_02_easy ...] [--windows 0.2 1 2] [--models euroc_calibrated euroc]
[--align auto] (poses moved onto the IMU's clock and frame first, as ``eval --align auto``)
"""

import argparse
from pathlib import Path

from denoise_imu_ros.core.modelfile import gyro_covariance, read_model_file
from denoise_imu_ros.data.load import load_sequence
from denoise_imu_ros.evaluation.correct import corrected_gyro
from denoise_imu_ros.evaluation.preintegration import (
    errors, GRAVITY, ground_truth_velocity, Increments, preintegrate, reference, window_starts)
from denoise_imu_ros.pipeline.covariance import variances
from denoise_imu_ros.runtime.settings import Settings
import gtsam
import numpy as np

DATA = Path(__file__).resolve().parents[2] / 'shared' / 'data' / 'euroc'
TEST = ['MH_02_easy', 'MH_04_difficult', 'V1_01_easy', 'V1_03_difficult', 'V2_02_medium']
# EuRoC's imu0/sensor.yaml (ADIS16448): white noise densities, per sqrt(Hz)
GYRO_DENSITY, ACCEL_DENSITY = 1.6968e-4, 2.0e-3


def gtsam_increments(gyro: np.ndarray, accel: np.ndarray, stamp_s: np.ndarray,
                     starts: np.ndarray, length: int, gyro_var: np.ndarray,
                     accel_var: np.ndarray) -> Increments:
    """
    Pre-integrate each window with GTSAM, each sample's covariances its own.

    The parameters are shared with the pre-integration, which reads them at every sample:
    set before each, they give that sample's covariances.
    """
    dt = np.diff(stamp_s)
    params = gtsam.PreintegrationParams.MakeSharedU(GRAVITY)
    # GTSAM takes continuous-time densities: a sample's variance times its period
    params.setGyroscopeCovariance(np.diag(gyro_var[0] * dt[0]))
    params.setAccelerometerCovariance(np.diag(accel_var[0] * dt[0]))
    varies = not ((gyro_var == gyro_var[0]).all() and (accel_var == accel_var[0]).all())
    params.setIntegrationCovariance(np.zeros((3, 3)))
    pim = gtsam.PreintegratedImuMeasurements(params, gtsam.imuBias.ConstantBias())
    rot, vel, pos, cov = [], [], [], []
    order = [0, 1, 2, 6, 7, 8, 3, 4, 5]  # GTSAM's (rotation, position, velocity) to ours
    for s in starts:
        pim.resetIntegration()
        for k in range(s, s + length):
            if varies:
                params.setGyroscopeCovariance(np.diag(gyro_var[k] * dt[k]))
                params.setAccelerometerCovariance(np.diag(accel_var[k] * dt[k]))
            pim.integrateMeasurement(accel[k], gyro[k], dt[k])
        rot.append(pim.deltaRij().matrix())
        vel.append(pim.deltaVij())
        pos.append(pim.deltaPij())
        # GTSAM's rotation coordinates: dR = Exp(theta); ours: dR Exp(phi), phi = J_r theta
        jac = np.eye(9)
        jac[:3, :3] = gtsam.Rot3.ExpmapDerivative(gtsam.Rot3.Logmap(pim.deltaRij()))
        cov.append(jac @ pim.preintMeasCov()[np.ix_(order, order)] @ jac.T)
    return Increments(np.array(rot), np.array(vel), np.array(pos), np.array(cov))


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument('--data', default=str(DATA))
    parser.add_argument('--sequences', nargs='+', default=TEST)
    parser.add_argument('--models', nargs='+', default=['euroc_calibrated', 'euroc'],
                        help='shipped names or model files, each a row (its file name)')
    parser.add_argument('--windows', nargs='+', type=float, default=[0.2, 1.0, 2.0],
                        help='window lengths (s)')
    parser.add_argument('--align', choices=('none', 'auto'), default='none',
                        help="auto: the poses moved onto the IMU's clock and frame first")
    args = parser.parse_args()
    models = {Path(name).stem: read_model_file(name) for name in args.models}
    rows: dict[tuple[float, str], list[dict[str, np.ndarray]]] = {}
    largest = {'increment': 0.0, 'covariance': 0.0}
    for name in args.sequences:
        seq = load_sequence(Path(args.data) / name, align_poses=args.align)
        stamp_s = (seq.stamp_ns - seq.stamp_ns[0]) * 1e-9
        rate = seq.rate_hz
        n = len(stamp_s)
        vel, vel_source = ground_truth_velocity(Path(args.data) / name, seq.stamp_ns,
                                                seq.gt_pos, stamp_s)
        datasheet = np.full((n, 3), ACCEL_DENSITY ** 2 * rate)
        imus = {'raw': (seq.imu[:, :3], seq.imu[:, 3:],
                        np.full((n, 3), GYRO_DENSITY ** 2 * rate), datasheet)}
        for label, mf in models.items():
            var = np.broadcast_to(np.diag(np.reshape(gyro_covariance(mf), (3, 3))), (n, 3))
            if not var.any():  # none in the file (zeros): the datasheet's, as for the raw gyro
                var = imus['raw'][2]
            # from the recording's first sample, as the node and process-bag run it
            stream = np.vstack([seq.lead_in, seq.imu])
            full = corrected_gyro(mf, stream)
            gyro = full[len(seq.lead_in):]
            bias = np.array(Settings().corrected_accel_bias(mf))  # the node's, at defaults
            imus[f'{label}, accelerometer as it came'] = (gyro, seq.imu[:, 3:], var, datasheet)
            spec, accel_spec = mf.meta.gyro_variance, mf.meta.accel_variance
            accel_var = datasheet
            if spec is not None:
                imus[f'{label}, its validation residual'] = (gyro, seq.imu[:, 3:] - bias, var,
                                                             datasheet)
                var = np.repeat(variances(full, stream[:, 3:], rate, spec)[
                    len(seq.lead_in):, None], 3, axis=1)
            if accel_spec is not None and Settings().per_sample_accel(mf):  # as published
                imus[f'{label}, its gyro variance'] = (gyro, seq.imu[:, 3:] - bias, var,
                                                       datasheet)
                accel_var = np.repeat(variances(full, stream[:, 3:], rate, accel_spec)[
                    len(seq.lead_in):, None], 3, axis=1)
            imus[label] = (gyro, seq.imu[:, 3:] - bias, var, accel_var)
        for window_s in args.windows:
            length = int(round(window_s * rate))
            starts = window_starts(seq.gt_valid, length)
            ref = reference(seq.gt_quat, seq.gt_pos, vel, stamp_s, starts, length)
            for label, (gyro, accel, gyro_var, accel_var) in imus.items():
                ours = preintegrate(gyro, accel, stamp_s, starts, length, gyro_var, accel_var)
                theirs = gtsam_increments(gyro, accel, stamp_s, starts, length, gyro_var,
                                          accel_var)
                largest['increment'] = max(
                    largest['increment'], *(float(np.abs(a - b).max()) for a, b in (
                        (ours.rotation, theirs.rotation), (ours.velocity, theirs.velocity),
                        (ours.position, theirs.position))))
                rel = np.abs(ours.covariance - theirs.covariance) / (
                    np.abs(theirs.covariance).max(axis=(1, 2), keepdims=True))
                largest['covariance'] = max(largest['covariance'], float(rel.max()))
                rows.setdefault((window_s, label), []).append(errors(theirs, ref))
        print(f'{name}: {len(seq.imu)} samples, velocity from its {vel_source}', flush=True)
    print('\n| window | IMU | rotation (deg) | velocity (m/s) | position (m) | NEES rotation '
          '(in 2 sigma) | NEES velocity (in 2 sigma) | windows |')
    print('|---|---|---|---|---|---|---|---|')
    for (window_s, label), per_seq in rows.items():
        err = {k: np.concatenate([e[k] for e in per_seq]) for k in per_seq[0]}

        def rms(key: str) -> float:
            return float(np.sqrt(np.mean(err[key] ** 2)))
        print(f'| {window_s:g} s | {label} | {rms("rotation_deg"):.3f} | '
              f'{rms("velocity_m_s"):.3f} | {rms("position_m"):.3f} | '
              f'{err["nees_rotation"].mean():.3g} ({(err["nees_rotation"] < 4).mean():.0%}) | '
              f'{err["nees_velocity"].mean():.3g} ({(err["nees_velocity"] < 4).mean():.0%}) | '
              f'{len(err["rotation_deg"])} |')
    print(f"\nGTSAM's increments against ours: largest difference {largest['increment']:.2g} "
          f"(rotation matrix entries, m/s, m); of a covariance entry {largest['covariance']:.2g} "
          'of its largest')


if __name__ == '__main__':
    main()

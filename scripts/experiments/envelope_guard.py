# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Does a model fail where its input leaves what it was trained on? An experiment.

BROAD networks trained on session C (slow motion: at most 325 deg/s, accelerations near
gravity) fail on session B's fast trials (600-1450 deg/s, 87 m/s^2 beyond gravity). This
takes a model's training envelope (the largest gyro norm and the largest distance of the
accelerometer norm from gravity, or a high percentile of each, over its training
recordings) and, wherever a sample of the receptive field leaves it, replaces the model's
output by the raw gyro less its turn-on bias (the "rest bias" row). Prints, per held-out
recording, the open-loop AOE and the AOE of VQF (defaults) fed each gyro: rest bias, the
model, the model so guarded (per envelope), and the share of samples guarded; then,
with the largest-value envelope, where the guard goes relative to the output's bias
tracking: first (the tracker fed the guarded gyro), last (the tracker fed the model's
output), or the tracker fed the guarded gyro with untrusted samples left untracked; and,
the guard last, the tracker's estimate held (restored after each stretch) wherever the
guard is, or only where the receptive field turns faster than the envelope (what ships,
``envelope.finish``, there on the model's input and with its stored envelope), or there
with the tracker fed the fallback through those stretches.
Usage: .venv/bin/python scripts/experiments/envelope_guard.py MODEL DATA_DIR
       TRAIN_A,TRAIN_B,... HELD_A,HELD_B,...
"""

from pathlib import Path
import sys

from denoise_imu_ros.core.metrics import score
from denoise_imu_ros.core.schema import InputEnvelope
from denoise_imu_ros.data import envelope, rest_bias
from denoise_imu_ros.data.load import load_sequence
from denoise_imu_ros.evaluation import filters
from denoise_imu_ros.learn.checkpoint import load_model
from denoise_imu_ros.learn.model import correct_gyro
import numpy as np

PERCENTILES = (100.0, 99.9, 99.0)


def fused_aoe(seq, gyro: np.ndarray) -> float:
    """AOE of VQF's defaults fed this gyro and the recording's accelerometer (deg)."""
    quat = filters.run(filters.Filter('vqf'), gyro, seq.imu[:, 3:], seq.rate_hz, seq.stamp_ns)
    return filters.score(seq, quat).aoe


def main(model: str, data: str, trained: list[str], held: list[str]) -> None:
    """Print the envelopes, then one line per held-out recording and the means."""
    net = load_model(model)
    align = net.meta.recipe('align', 'none')
    field = net.model.receptive_field
    train = [envelope.excursion(load_sequence(Path(data) / n, align_poses=align).imu)
             for n in trained]
    gyro_all = np.concatenate([g for g, _ in train])
    accel_all = np.concatenate([a for _, a in train])
    envelopes = {p: InputEnvelope(float(np.percentile(gyro_all, p)),
                                  float(np.percentile(accel_all, p))) for p in PERCENTILES}
    for p, e in envelopes.items():
        print(f'envelope p{p:g}: gyro {np.degrees(e.gyro_rad_s):.0f} deg/s, accel '
              f'{e.accel_offset_m_s2:.1f} m/s^2 off g')
    settings = rest_bias.baseline_settings(net.meta)
    rows = []
    for name in held:
        seq = load_sequence(Path(data) / name, align_poses=align)
        rest = rest_bias.remove_rest_bias(seq.imu, seq.rate_hz, settings)[:, :3]

        def track(gyro: np.ndarray, hold: np.ndarray | None = None) -> np.ndarray:
            return rest_bias.track_bias(gyro, seq.imu[:, 3:], seq.rate_hz,
                                        net.meta.bias_tracking, hold)

        fed = rest_bias.model_input(net, seq.imu)
        output = correct_gyro(net.model, fed)
        gyro = track(output)
        figures = [score(seq, rest)['aoe_deg'], score(seq, gyro)['aoe_deg']]
        fused = [fused_aoe(seq, rest), fused_aoe(seq, gyro)]
        shares = []
        for p in PERCENTILES:
            out = envelope.untrusted(seq.imu, envelopes[p], field)
            guarded = np.where(out[:, None], rest, gyro)
            figures.append(score(seq, guarded)['aoe_deg'])
            fused.append(fused_aoe(seq, guarded))
            shares.append(out.mean())
        out = envelope.untrusted(seq.imu, envelopes[100.0], field)[:, None]
        guarded = np.where(out, rest, output)
        fast = envelope.too_fast(seq.imu, envelopes[100.0], field)
        placement = [score(seq, g)['aoe_deg'] for g in (
            track(guarded), np.where(out, rest, gyro), np.where(out, rest, track(guarded)),
            np.where(out, rest, track(output, out[:, 0])),
            np.where(out, rest, track(output, fast)),
            np.where(out, rest, track(np.where(fast[:, None], rest, output), fast)))]
        rows.append((figures, fused, placement))
        print(f'{name[:34]:34s} open loop ' + ' '.join(f'{v:6.2f}' for v in figures)
              + '  fused ' + ' '.join(f'{v:6.2f}' for v in fused)
              + '  guarded ' + ' '.join(f'{100 * s:3.0f}%' for s in shares)
              + '  first/last/untracked/held/held-fast/fed-fallback '
              + ' '.join(f'{v:6.2f}' for v in placement),
              flush=True)
    mean = [np.mean([r[k] for r in rows], 0) for k in range(3)]
    print('columns: rest bias, model, guarded by p' + ', p'.join(f'{p:g}' for p in PERCENTILES))
    print(f'{"mean":34s} open loop ' + ' '.join(f'{v:6.2f}' for v in mean[0])
          + '  fused ' + ' '.join(f'{v:6.2f}' for v in mean[1])
          + '  first/last/untracked/held/held-fast/fed-fallback '
          + ' '.join(f'{v:6.2f}' for v in mean[2]))


if __name__ == '__main__':
    main(sys.argv[1], sys.argv[2], sys.argv[3].split(','), sys.argv[4].split(','))

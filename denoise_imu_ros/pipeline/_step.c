/*
 * SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
 * SPDX-License-Identifier: Apache-2.0
 *
 * One sample of the streaming network (streaming.py), compiled: the same buffers, the
 * same arithmetic, without a Python call per layer. Plain C, no Python API: loaded with
 * ctypes, so it needs a compiler when the package is built, never at run time.
 * streaming.py keeps the numpy step, used where this library was not built.
 */

#include <math.h>
#include <stdint.h>
#include <string.h>

/* One hidden layer: its input history, taps-then-1 column, weights with the bias last. */
typedef struct {
    int64_t groups, c_in, c_out;   /* c_in, c_out per group */
    int64_t kernel, dilation, span, rows;
    int64_t *pos;                  /* newest history row, shared with Python */
    float *hist;                   /* groups x rows x c_in */
    float *col;                    /* groups x (kernel * c_in + 1), last entry 1 */
    float *weight;                 /* groups x c_out x (kernel * c_in + 1) */
    float *out;                    /* groups x c_out */
} layer_t;

/* The whole network: hidden layers, then the output layer and the calibration. */
typedef struct {
    int64_t n_layers;
    layer_t *layers;
    const double *imu;             /* (6,) the raw sample */
    float *x0;                     /* (6,) the raw sample as float32 */
    const double *calib;           /* (3, 3) I + Delta */
    const float *out_weight;       /* (3, out_cols): the output layer, its bias last */
    int64_t out_cols;
    const float *out_in;           /* (out_cols,) the last hidden output, then 1 */
    double *gyro;                  /* (3,) the corrected gyro */
} net_t;

/* AVX2 and FMA where the CPU has them (the x86-64-v3 ISA level, whatever its maker: a CPU
 * model such as arch=haswell would be chosen on that model alone), chosen when the library
 * is loaded (x86-64). */
#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__)
#define CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define CLONES
#endif

CLONES static float dot(const float *a, const float *b, int64_t n)
{
    float acc = 0.0f;
#pragma omp simd reduction(+:acc)
    for (int64_t i = 0; i < n; i++) {
        acc += a[i] * b[i];
    }
    return acc;
}

/* y = W x, W (rows, n) row-major: four rows at a time, so that each load of x feeds
 * four independent sums (one sum alone waits on its own additions). */
CLONES static void matvec(const float *w, const float *x, int64_t rows, int64_t n, float *y)
{
    int64_t o = 0;
    for (; o + 4 <= rows; o += 4) {
        const float *w0 = w + o * n, *w1 = w0 + n, *w2 = w1 + n, *w3 = w2 + n;
        float a0 = 0.0f, a1 = 0.0f, a2 = 0.0f, a3 = 0.0f;
#pragma omp simd reduction(+:a0, a1, a2, a3)
        for (int64_t i = 0; i < n; i++) {
            a0 += w0[i] * x[i];
            a1 += w1[i] * x[i];
            a2 += w2[i] * x[i];
            a3 += w3[i] * x[i];
        }
        y[o] = a0;
        y[o + 1] = a1;
        y[o + 2] = a2;
        y[o + 3] = a3;
    }
    for (; o < rows; o++) {
        y[o] = dot(w + o * n, x, n);
    }
}

/* GELU as torch's (erf-based); exactly 0 below -10, as the numpy step's table. */
static float gelu(float x)
{
    return x < -10.0f ? 0.0f : 0.5f * x * (1.0f + erff(x * 0.70710678118654752f));
}

static void layer_step(layer_t *ly, const float *x)
{
    const int64_t c = ly->c_in, n = ly->kernel * c + 1;
    int64_t pos = *ly->pos;
    if (pos + 1 == ly->rows) {  /* full: keep the last span - 1 rows */
        for (int64_t g = 0; g < ly->groups; g++) {
            float *h = ly->hist + g * ly->rows * c;
            memmove(h, h + (pos - ly->span + 2) * c, (size_t)((ly->span - 1) * c) * sizeof(float));
        }
        pos = ly->span - 2;
    }
    *ly->pos = ++pos;
    for (int64_t g = 0; g < ly->groups; g++) {
        float *h = ly->hist + g * ly->rows * c, *col = ly->col + g * n;
        memcpy(h + pos * c, x + g * c, (size_t)c * sizeof(float));
        for (int64_t j = 0; j < ly->kernel; j++) {  /* taps, oldest first */
            memcpy(col + j * c, h + (pos - (ly->kernel - 1 - j) * ly->dilation) * c,
                   (size_t)c * sizeof(float));
        }
        float *out = ly->out + g * ly->c_out;
        matvec(ly->weight + g * ly->c_out * n, col, ly->c_out, n, out);
        for (int64_t o = 0; o < ly->c_out; o++) {
            out[o] = gelu(out[o]);
        }
    }
}

void net_step(net_t *net)
{
    for (int i = 0; i < 6; i++) {
        net->x0[i] = (float)net->imu[i];
    }
    const float *x = net->x0;
    for (int64_t l = 0; l < net->n_layers; l++) {
        layer_step(&net->layers[l], x);
        x = net->layers[l].out;
    }
    for (int r = 0; r < 3; r++) {
        double g = 0.0;
        for (int c = 0; c < 3; c++) {
            g += net->calib[3 * r + c] * net->imu[c];
        }
        net->gyro[r] = g + dot(net->out_weight + r * net->out_cols, net->out_in, net->out_cols);
    }
}

/*
 * SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
 * SPDX-License-Identifier: Apache-2.0
 *
 * A hidden block's element-wise layers in training, fused (learn/fused.py): BatchNorm with
 * the batch's statistics, exact GELU and inverted dropout over a (rows, channels, length)
 * float32 tensor, forward and backward, each in two passes over memory where PyTorch's
 * separate layers take a dozen. The dropout mask is a hash of (seed, element), so the
 * backward recomputes it instead of storing it. Plain C, no Python API: loaded with
 * ctypes; fused.py keeps PyTorch's layers where this library was not built.
 */

#include <math.h>
#include <stdint.h>
#include <string.h>

/* x86-64 ISA levels, chosen when the library is loaded: AVX-512, AVX2 with FMA, the base
 * (a CPU model such as arch=haswell would be chosen on that model alone) */
#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__)
#define CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#define INLINE static inline __attribute__((always_inline))
#else
#define CLONES
#define INLINE static inline
#endif

#define CHUNK 512  /* float partial sums this long, then added in double */

/* murmur3's 32-bit finaliser: every input bit moves every output bit */
INLINE uint32_t mix(uint32_t h)
{
    h ^= h >> 16;
    h *= 0x85ebca6bu;
    h ^= h >> 13;
    h *= 0xc2b2ae35u;
    h ^= h >> 16;
    return h;
}

INLINE uint32_t row_key(uint64_t seed, int64_t row)
{
    return mix((uint32_t)seed ^ mix((uint32_t)(seed >> 32) + (uint32_t)row * 0x9e3779b9u));
}

/* dropout's factor for element t of a row: keep when its 32-bit draw is at least the
 * threshold (p * 2^32), else 0; compared as signed integers, which AVX2 has */
INLINE float mask(uint32_t key, int64_t t, int32_t threshold, float keep)
{
    int32_t draw = (int32_t)(mix(key ^ ((uint32_t)t * 0x9e3779b1u)) ^ 0x80000000u);
    return draw >= threshold ? keep : 0.0f;
}

/* exp(x) for x in [-87, 0]: 2^k exp(r), |r| <= ln2 / 2, Cephes' polynomial for exp(r) */
INLINE float exp_neg(float x)
{
    x = x < -87.0f ? -87.0f : x;
    float k = (x * 1.44269504f + 12582912.0f) - 12582912.0f;  /* rounded: 1.5 * 2^23 */
    float r = x - k * 0.693359375f + k * 2.12194440e-4f;
    float p = 1.9875691500e-4f;
    p = p * r + 1.3981999507e-3f;
    p = p * r + 8.3334519073e-3f;
    p = p * r + 4.1665795894e-2f;
    p = p * r + 1.6666665459e-1f;
    p = p * r + 5.0000001201e-1f;
    p = p * r * r + r + 1.0f;
    int32_t bits = ((int32_t)k + 127) << 23;
    float scale;
    memcpy(&scale, &bits, sizeof scale);
    return p * scale;
}

/* Phi(y), the normal CDF, and phi(y), its density: Abramowitz & Stegun 7.1.26 for erfc
 * (absolute error below 1.5e-7), taken on |y| so that neither tail cancels */
INLINE void normal(float y, float *cdf, float *pdf)
{
    float z = fabsf(y) * 0.70710678f;
    float t = 1.0f / (1.0f + 0.3275911f * z);
    float e = exp_neg(-z * z);
    float q = 1.061405429f;
    q = q * t - 1.453152027f;
    q = q * t + 1.421413741f;
    q = q * t - 0.284496736f;
    q = q * t + 0.254829592f;
    float tail = 0.5f * q * t * e;  /* Phi(-|y|) */
    *cdf = y < 0.0f ? tail : 1.0f - tail;
    *pdf = 0.39894228f * e;
}

/* Per-channel sums of (x - center) and (x - center)^2 over rows and length, added to
 * sums[0:channels] and sums[channels:2 channels] */
CLONES void block_sums(const float *x, int64_t rows, int64_t channels, int64_t length,
                       const float *center, double *sums)
{
    for (int64_t row = 0; row < rows * channels; row++) {
        int64_t c = row % channels;
        const float *xr = x + row * length;
        float m = center[c];
        for (int64_t t0 = 0; t0 < length; t0 += CHUNK) {
            int64_t t1 = t0 + CHUNK < length ? t0 + CHUNK : length;
            float s1 = 0.0f, s2 = 0.0f;
#pragma omp simd reduction(+:s1, s2)
            for (int64_t t = t0; t < t1; t++) {
                float d = xr[t] - m;
                s1 += d;
                s2 += d * d;
            }
            sums[c] += s1;
            sums[channels + c] += s2;
        }
    }
}

/* out = dropout(GELU(scale * x + shift)): kept elements times keep, the others 0 */
CLONES void block_forward(const float *x, float *out, int64_t rows, int64_t channels,
                          int64_t length, const float *scale, const float *shift, float keep,
                          int32_t threshold, uint64_t seed)
{
    for (int64_t row = 0; row < rows * channels; row++) {
        int64_t c = row % channels;
        const float *xr = x + row * length;
        float *o = out + row * length;
        float a = scale[c], b = shift[c];
        uint32_t key = row_key(seed, row);
#pragma omp simd
        for (int64_t t = 0; t < length; t++) {
            float y = a * xr[t] + b, cdf, pdf;
            normal(y, &cdf, &pdf);
            float m = mask(key, t, threshold, keep);
            o[t] = m * y * cdf;
        }
    }
}

/* The gradient through dropout and GELU, dy = grad * mask * GELU'(scale * x + shift),
 * written to dy; per-channel sums of dy and dy * (x - mean) added to sums[0:channels] and
 * sums[channels:2 channels] (BatchNorm's backward needs them over the whole batch) */
CLONES void block_backward_sums(const float *grad, const float *x, float *dy, int64_t rows,
                                int64_t channels, int64_t length, const float *scale,
                                const float *shift, const float *mean, float keep,
                                int32_t threshold, uint64_t seed, double *sums)
{
    for (int64_t row = 0; row < rows * channels; row++) {
        int64_t c = row % channels;
        const float *g = grad + row * length, *xr = x + row * length;
        float *d = dy + row * length;
        float a = scale[c], b = shift[c], m0 = mean[c];
        uint32_t key = row_key(seed, row);
        for (int64_t t0 = 0; t0 < length; t0 += CHUNK) {
            int64_t t1 = t0 + CHUNK < length ? t0 + CHUNK : length;
            float s1 = 0.0f, s2 = 0.0f;
#pragma omp simd reduction(+:s1, s2)
            for (int64_t t = t0; t < t1; t++) {
                float y = a * xr[t] + b, cdf, pdf;
                normal(y, &cdf, &pdf);
                float m = mask(key, t, threshold, keep);
                float v = g[t] * m * (cdf + y * pdf);
                d[t] = v;
                s1 += v;
                s2 += v * (xr[t] - m0);
            }
            sums[c] += s1;
            sums[channels + c] += s2;
        }
    }
}

/* BatchNorm's input gradient in place of dy: dx = a dy + b x + c, per channel */
CLONES void block_backward_input(float *dy, const float *x, int64_t rows, int64_t channels,
                                 int64_t length, const float *a, const float *b,
                                 const float *c)
{
    for (int64_t row = 0; row < rows * channels; row++) {
        int64_t k = row % channels;
        float *d = dy + row * length;
        const float *xr = x + row * length;
        float ak = a[k], bk = b[k], ck = c[k];
#pragma omp simd
        for (int64_t t = 0; t < length; t++) {
            d[t] = ak * d[t] + bk * xr[t] + ck;
        }
    }
}

/*
 * Portable C decoder of the accelerometer calibration blob (format versions 1 and 2) and the device's
 * per-sample compensation, for C firmware. C99, no allocation, no libc beyond <stdint.h>,
 * <stddef.h> and <math.h> (isfinite only). Compile acal_blob.c with -ffp-contract=off (no fused
 * multiply-add) for results bit for bit equal to the Rust device code: both then evaluate the same
 * single-precision operations in the same order.
 *
 * Blob layout (little-endian): "ACAL", u16 version (1 or 2), u16 payload length n, n bytes of postcard
 * payload, u32 CRC-32/ISO-HDLC of everything before it. Postcard writes f64 as 8 bytes, enum variants
 * and u64 as varints (LEB128), an Option as one byte 0 (absent) or 1 followed by the value.
 *
 * Version 1 payload: unit id (12 bytes), output unit (varint: 0 V, 1 LSB, 2 m/s^2, 3 g), zero biases
 * (3 f64), scale factors (3 f64), installation angles (9 f64, degrees, row-major), lever arms (9 f64,
 * m, row i = sensing point i), reference point (varint: 0 table axis, 1 centroid, 2 body point
 * followed by 3 f64 m), gravity (f64, m/s^2), creation time (varint u64).
 *
 * Version 2 payload: version 1's, then two Options:
 *   gyro correction (docs/model.md section 8): G (9 f64, row-major, w = G omega + b), b (3 f64, rad/s);
 *   temperature model (docs/model.md section 9): reference (f64, deg C), valid range (2 f64, deg C),
 *   zero-bias polynomials (9 f64), relative-scale polynomials (9 f64), then an Option of the gyro-bias
 *   polynomials (9 f64, rad/s); row i holds c_i1, c_i2, c_i3 of c_i1 dT + c_i2 dT^2 + c_i3 dT^3.
 * A version 1 blob decodes as version 2 with both sections absent.
 *
 * Per sample, as the device: acal_correct_rate (gyro), your angular-acceleration estimate from the
 * corrected rate, then acal_compensate; with a temperature model, acal_refresh a few times a second.
 */
#ifndef ACAL_BLOB_H
#define ACAL_BLOB_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** The format version the host writes; acal_decode also reads ACAL_BLOB_VERSION_1. */
#define ACAL_BLOB_VERSION 2u
#define ACAL_BLOB_VERSION_1 1u

/** The gyro's measurement model w = G omega + b (docs/model.md section 8). */
struct acal_gyro {
    double matrix[3][3];              /* G, row-major, dimensionless: row i is gyro axis i */
    double bias_rad_s[3];             /* b at the reference temperature, rad/s, gyro axes */
};

/**
 * How the parameters move with temperature (docs/model.md section 9), dT = T - reference_c:
 * u0_i(T) = u0_i + P_i(dT), M(T) = diag(1 + S(dT)) M, b_j(T) = b_j + B_j(dT).
 */
struct acal_temperature {
    double reference_c;
    double valid_range_c[2];                 /* [low, high] */
    double zero_bias_out_per_c[3][3];        /* P_i: output unit per deg C^k */
    double scale_rel_per_c[3][3];            /* S_i: 1 per deg C^k */
    uint8_t has_gyro_bias_per_c;             /* 0: the gyro bias does not change (zeros below) */
    double gyro_bias_rad_s_per_c[3][3];      /* B_j: rad/s per deg C^k */
};

/** The calibration as stored in the blob (the paper's parameters, docs/model.md sections 1-3). */
struct acal_calibration {
    uint8_t unit_id[12];
    uint8_t output_unit;              /* 0: volts, 1: LSB, 2: m/s^2, 3: g */
    double zero_bias_out[3];          /* u0, output unit */
    double scale_out_per_g[3];        /* k, output unit per g */
    double installation_angles_deg[3][3];
    double lever_arms_m[3][3];        /* row i: sensing point of accelerometer i */
    uint8_t reference;                /* 0 table axis, 1 centroid, 2 body point */
    double reference_offset_m[3];     /* with reference 2; zeros otherwise */
    double gravity_m_s2;
    uint64_t created_unix_s;          /* 0: unknown */
    uint8_t has_gyro;                 /* 0: absent, a perfect gyro (gyro holds G = I, b = 0) */
    struct acal_gyro gyro;
    uint8_t has_temperature;          /* 0: absent, no temperature model (all zeros below) */
    struct acal_temperature temperature;
};

/**
 * The device's precomputed per-sample constants (f_O = g K_A (U - u0 - K d), docs/model.md 10) and its
 * gyro correction (omega = c + G^-1 w, c = -G^-1 b(T), docs/model.md 8). With a temperature model,
 * copy ACAL_COMPENSATOR into a variable and let acal_refresh() update it a few times a second.
 */
struct acal_compensator {
    float zero_bias_out[3];
    float ka_m_s2_per_out[3][3];
    float a[3][3];
    float p[3][3];
    float q[3][3];
    float s[3];
    float gyro_offset_rad_s[3];       /* c = -G^-1 b(T), rad/s, body axes */
    float gyro_inv[3][3];             /* G^-1, row-major */
    uint8_t gyro_corrected;           /* 0: a perfect gyro without drift, the rate passes through */
};

/**
 * What acal_refresh() starts from (ACAL_THERMAL of a calibration with a temperature model): the
 * constants at the reference temperature and the polynomials of docs/model.md 9 in float, row i
 * holding c_i1, c_i2, c_i3 of c_i1 dT + c_i2 dT^2 + c_i3 dT^3.
 */
struct acal_thermal {
    float reference_c;
    float range_c[2];                 /* [low, high]: a temperature outside is clamped to it */
    float zero_bias_out[3];
    float ka_m_s2_per_out[3][3];
    float p[3][3];
    float q[3][3];
    float s[3];
    float gyro_bias_rad_s[3];
    float zero_bias_poly[3][3];       /* output unit per deg C^k */
    float scale_poly[3][3];           /* relative scale, 1 per deg C^k */
    float gyro_bias_poly[3][3];       /* rad/s per deg C^k */
};

enum acal_temperature_state {
    ACAL_TEMPERATURE_IN_RANGE = 0,    /* the terms are those at temp_c */
    ACAL_TEMPERATURE_CLAMPED,         /* outside the valid range: those at its nearest end (flag it) */
    ACAL_TEMPERATURE_NO_READING       /* temp_c not finite: the terms are unchanged (flag it) */
};

enum acal_error {
    ACAL_OK = 0,
    ACAL_TOO_SHORT,
    ACAL_BAD_MAGIC,
    ACAL_UNSUPPORTED_VERSION,
    ACAL_LENGTH_MISMATCH,
    ACAL_CRC_MISMATCH,
    ACAL_MALFORMED,
    ACAL_NON_FINITE
};

/** CRC-32/ISO-HDLC (the zlib CRC). */
uint32_t acal_crc32(const uint8_t *data, size_t len);

/**
 * Decodes a blob of exactly len bytes, version 1 or 2 (any other version: ACAL_UNSUPPORTED_VERSION).
 * Checks length, magic, version, CRC, the payload's structure exactly as postcard reads it (varint
 * lengths, Option bytes 0 or 1, no trailing bytes) and that every value is finite; the physical checks (invertible K A, plausible gravity) are the
 * device's and the host's, not repeated here. On error *out is unspecified.
 */
enum acal_error acal_decode(const uint8_t *blob, size_t len, struct acal_calibration *out);

/**
 * The body rate from the gyro's output, omega = G^-1 (w - b) evaluated as c + G^-1 w (9 multiply-adds;
 * a perfect gyro passes w through). Apply it before estimating the angular acceleration.
 */
void acal_correct_rate(const struct acal_compensator *c, const float w_rad_s[3],
                       float omega_rad_s[3]);

/**
 * Recomputes the temperature-dependent terms of c (zero biases, the columns of K_A, the lever-arm
 * terms, the gyro bias and its offset) for the unit's temperature temp_c, deg C, from th. Call it a
 * few times a second, not per sample (it divides three times).
 */
enum acal_temperature_state acal_refresh(struct acal_compensator *c, const struct acal_thermal *th,
                                         float temp_c);

/**
 * Full compensation: specific force at the reference point, m/s^2. w_rad_s and wd_rad_s2 are the body
 * rate and angular acceleration, i.e. the gyro's output corrected by acal_correct_rate().
 */
void acal_compensate(const struct acal_compensator *c, const float u[3], const float w_rad_s[3],
                     const float wd_rad_s2[3], float f_m_s2[3]);

/** Static-only compensation (paper eq. 6). */
void acal_compensate_static(const struct acal_compensator *c, const float u[3], float f_m_s2[3]);

#ifdef __cplusplus
}
#endif

#endif /* ACAL_BLOB_H */

/*
 * Portable C decoder of the accelerometer calibration blob (format version 1) and the device's
 * per-sample compensation, for C firmware. C99, no allocation, no libc beyond <stdint.h>,
 * <stddef.h> and <math.h> (isfinite only). Compile acal_blob.c with -ffp-contract=off (no fused
 * multiply-add) for results bit for bit equal to the Rust device code: both then evaluate the same
 * single-precision operations in the same order.
 *
 * Blob layout (little-endian): "ACAL", u16 version (1), u16 payload length n, n bytes of postcard
 * payload, u32 CRC-32/ISO-HDLC of everything before it. The payload: unit id (12 bytes), output unit
 * (varint: 0 V, 1 LSB), zero biases (3 f64), scale factors (3 f64), installation angles (9 f64,
 * degrees, row-major), lever arms (9 f64, m, row i = sensing point i), reference point (varint: 0 table
 * axis, 1 centroid, 2 body point followed by 3 f64 m), gravity (f64, m/s^2), creation time (varint u64).
 */
#ifndef ACAL_BLOB_H
#define ACAL_BLOB_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define ACAL_BLOB_VERSION 1u

/** The calibration as stored in the blob (the paper's parameters, docs/model.md sections 1-3). */
struct acal_calibration {
    uint8_t unit_id[12];
    uint8_t output_unit;              /* 0: volts, 1: LSB */
    double zero_bias_out[3];          /* u0, output unit */
    double scale_out_per_g[3];        /* k, output unit per g */
    double installation_angles_deg[3][3];
    double lever_arms_m[3][3];        /* row i: sensing point of accelerometer i */
    uint8_t reference;                /* 0 table axis, 1 centroid, 2 body point */
    double reference_offset_m[3];     /* with reference 2; zeros otherwise */
    double gravity_m_s2;
    uint64_t created_unix_s;          /* 0: unknown */
};

/** The device's precomputed per-sample constants (f_O = g K_A (U - u0 - K d), docs/model.md 10). */
struct acal_compensator {
    float zero_bias_out[3];
    float ka_m_s2_per_out[3][3];
    float a[3][3];
    float p[3][3];
    float q[3][3];
    float s[3];
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
 * Decodes a blob of exactly len bytes. Checks length, magic, version, CRC, the payload's structure
 * and that every value is finite; the physical checks (invertible K A, plausible gravity) are the
 * device's and the host's, not repeated here. On error *out is unspecified.
 */
enum acal_error acal_decode(const uint8_t *blob, size_t len, struct acal_calibration *out);

/** Full compensation: specific force at the reference point, m/s^2. */
void acal_compensate(const struct acal_compensator *c, const float u[3], const float w_rad_s[3],
                     const float wd_rad_s2[3], float f_m_s2[3]);

/** Static-only compensation (paper eq. 6). */
void acal_compensate_static(const struct acal_compensator *c, const float u[3], float f_m_s2[3]);

#ifdef __cplusplus
}
#endif

#endif /* ACAL_BLOB_H */

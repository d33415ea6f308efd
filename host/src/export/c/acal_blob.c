/* See acal_blob.h. */
#include "acal_blob.h"

#include <math.h>

uint32_t acal_crc32(const uint8_t *data, size_t len) {
    uint32_t crc = 0xFFFFFFFFu;
    for (size_t i = 0; i < len; i++) {
        crc ^= data[i];
        for (int b = 0; b < 8; b++) {
            crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
        }
    }
    return crc ^ 0xFFFFFFFFu;
}

struct reader {
    const uint8_t *p;
    size_t left;
    int ok;
};

static uint8_t take_u8(struct reader *r) {
    if (r->left < 1) {
        r->ok = 0;
        return 0;
    }
    r->left--;
    return *r->p++;
}

static double take_f64(struct reader *r) {
    uint64_t bits = 0;
    double v = 0.0;
    if (r->left < 8) {
        r->ok = 0;
        return 0.0;
    }
    for (int i = 7; i >= 0; i--) {
        bits = (bits << 8) | r->p[i];
    }
    r->p += 8;
    r->left -= 8;
    /* Type-pun through a union-free copy that every C99 compiler accepts. */
    {
        const unsigned char *src = (const unsigned char *)&bits;
        unsigned char *dst = (unsigned char *)&v;
        for (size_t i = 0; i < sizeof v; i++) {
            dst[i] = src[i];
        }
    }
    return v;
}

/* postcard varint (LEB128), at most 10 bytes for a u64. */
static uint64_t take_varint(struct reader *r) {
    uint64_t v = 0;
    for (int shift = 0; shift < 70; shift += 7) {
        uint8_t b = take_u8(r);
        if (!r->ok) {
            return 0;
        }
        v |= (uint64_t)(b & 0x7Fu) << shift;
        if ((b & 0x80u) == 0) {
            return v;
        }
    }
    r->ok = 0;
    return 0;
}

static void take_f64s(struct reader *r, double *out, int n) {
    for (int i = 0; i < n; i++) {
        out[i] = take_f64(r);
    }
}

static int all_finite(const double *v, int n) {
    for (int i = 0; i < n; i++) {
        if (!isfinite(v[i])) {
            return 0;
        }
    }
    return 1;
}

enum acal_error acal_decode(const uint8_t *blob, size_t len, struct acal_calibration *out) {
    struct reader r;
    size_t n;
    uint32_t stored;
    uint64_t unit, reference;
    if (len < 12) {
        return ACAL_TOO_SHORT;
    }
    if (blob[0] != 'A' || blob[1] != 'C' || blob[2] != 'A' || blob[3] != 'L') {
        return ACAL_BAD_MAGIC;
    }
    if ((uint16_t)(blob[4] | (blob[5] << 8)) != ACAL_BLOB_VERSION) {
        return ACAL_UNSUPPORTED_VERSION;
    }
    n = (size_t)(blob[6] | (blob[7] << 8));
    if (len != 8 + n + 4) {
        return ACAL_LENGTH_MISMATCH;
    }
    stored = (uint32_t)blob[8 + n] | ((uint32_t)blob[9 + n] << 8) | ((uint32_t)blob[10 + n] << 16) |
             ((uint32_t)blob[11 + n] << 24);
    if (acal_crc32(blob, 8 + n) != stored) {
        return ACAL_CRC_MISMATCH;
    }
    r.p = blob + 8;
    r.left = n;
    r.ok = 1;
    for (int i = 0; i < 12; i++) {
        out->unit_id[i] = take_u8(&r);
    }
    unit = take_varint(&r);
    out->output_unit = (uint8_t)unit;
    take_f64s(&r, out->zero_bias_out, 3);
    take_f64s(&r, out->scale_out_per_g, 3);
    take_f64s(&r, &out->installation_angles_deg[0][0], 9);
    take_f64s(&r, &out->lever_arms_m[0][0], 9);
    reference = take_varint(&r);
    out->reference = (uint8_t)reference;
    out->reference_offset_m[0] = out->reference_offset_m[1] = out->reference_offset_m[2] = 0.0;
    if (reference == 2) {
        take_f64s(&r, out->reference_offset_m, 3);
    }
    out->gravity_m_s2 = take_f64(&r);
    out->created_unix_s = take_varint(&r);
    if (!r.ok || r.left != 0 || unit > 1 || reference > 2) {
        return ACAL_MALFORMED;
    }
    if (!all_finite(out->zero_bias_out, 3) || !all_finite(out->scale_out_per_g, 3) ||
        !all_finite(&out->installation_angles_deg[0][0], 9) ||
        !all_finite(&out->lever_arms_m[0][0], 9) || !all_finite(out->reference_offset_m, 3) ||
        !isfinite(out->gravity_m_s2)) {
        return ACAL_NON_FINITE;
    }
    return ACAL_OK;
}

static void apply_ka(const struct acal_compensator *c, const float v[3], float f[3]) {
    for (int i = 0; i < 3; i++) {
        const float *m = c->ka_m_s2_per_out[i];
        f[i] = m[0] * v[0] + m[1] * v[1] + m[2] * v[2];
    }
}

void acal_compensate(const struct acal_compensator *c, const float u[3], const float w[3],
                     const float wd[3], float f_m_s2[3]) {
    float v[3];
    const float w2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
    for (int i = 0; i < 3; i++) {
        const float *p = c->p[i], *q = c->q[i], *a = c->a[i];
        const float tangential = wd[0] * p[0] + wd[1] * p[1] + wd[2] * p[2];
        const float a_w = a[0] * w[0] + a[1] * w[1] + a[2] * w[2];
        const float q_w = q[0] * w[0] + q[1] * w[1] + q[2] * w[2];
        const float k_d = tangential + a_w * q_w - w2 * c->s[i];
        v[i] = u[i] - c->zero_bias_out[i] - k_d;
    }
    apply_ka(c, v, f_m_s2);
}

void acal_compensate_static(const struct acal_compensator *c, const float u[3], float f_m_s2[3]) {
    float v[3];
    for (int i = 0; i < 3; i++) {
        v[i] = u[i] - c->zero_bias_out[i];
    }
    apply_ka(c, v, f_m_s2);
}

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

/*
 * postcard varint (LEB128) of a type of max_bytes bytes' worth: postcard refuses a varint longer than
 * max_bytes or whose last byte carries bits beyond the type (last_max), and so does this.
 * u32 (enum variants): 5 bytes, last byte <= 0x0F; u64: 10 bytes, last byte <= 0x01.
 */
static uint64_t take_varint(struct reader *r, int max_bytes, uint8_t last_max) {
    uint64_t v = 0;
    for (int i = 0; i < max_bytes; i++) {
        uint8_t b = take_u8(r);
        if (!r->ok) {
            return 0;
        }
        v |= (uint64_t)(b & 0x7Fu) << (7 * i);
        if ((b & 0x80u) == 0) {
            if (i == max_bytes - 1 && b > last_max) {
                break;
            }
            return v;
        }
    }
    r->ok = 0;
    return 0;
}

static uint64_t take_variant(struct reader *r) {
    return take_varint(r, 5, 0x0Fu);
}

/* postcard Option tag: 0 absent, 1 present, anything else malformed. */
static uint8_t take_option(struct reader *r) {
    uint8_t tag = take_u8(r);
    if (tag > 1) {
        r->ok = 0;
    }
    return tag;
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

static void zero(double *v, int n) {
    for (int i = 0; i < n; i++) {
        v[i] = 0.0;
    }
}

/* Version 2's optional sections; absent ones are a perfect gyro and an all-zero temperature model. */
static void take_sections(struct reader *r, struct acal_calibration *out) {
    struct acal_gyro *g = &out->gyro;
    struct acal_temperature *t = &out->temperature;
    out->has_gyro = take_option(r);
    if (out->has_gyro == 1) {
        take_f64s(r, &g->matrix[0][0], 9);
        take_f64s(r, g->bias_rad_s, 3);
    }
    out->has_temperature = r->ok ? take_option(r) : 0;
    if (out->has_temperature == 1) {
        t->reference_c = take_f64(r);
        take_f64s(r, t->valid_range_c, 2);
        take_f64s(r, &t->zero_bias_out_per_c[0][0], 9);
        take_f64s(r, &t->scale_rel_per_c[0][0], 9);
        t->has_gyro_bias_per_c = take_option(r);
        if (t->has_gyro_bias_per_c == 1) {
            take_f64s(r, &t->gyro_bias_rad_s_per_c[0][0], 9);
        }
    }
}

static void set_absent_sections(struct acal_calibration *out) {
    struct acal_temperature *t = &out->temperature;
    out->has_gyro = 0;
    zero(&out->gyro.matrix[0][0], 9);
    out->gyro.matrix[0][0] = out->gyro.matrix[1][1] = out->gyro.matrix[2][2] = 1.0;
    zero(out->gyro.bias_rad_s, 3);
    out->has_temperature = 0;
    t->reference_c = 0.0;
    zero(t->valid_range_c, 2);
    zero(&t->zero_bias_out_per_c[0][0], 9);
    zero(&t->scale_rel_per_c[0][0], 9);
    t->has_gyro_bias_per_c = 0;
    zero(&t->gyro_bias_rad_s_per_c[0][0], 9);
}

static int sections_finite(const struct acal_calibration *c) {
    const struct acal_temperature *t = &c->temperature;
    return all_finite(&c->gyro.matrix[0][0], 9) && all_finite(c->gyro.bias_rad_s, 3) &&
           isfinite(t->reference_c) && all_finite(t->valid_range_c, 2) &&
           all_finite(&t->zero_bias_out_per_c[0][0], 9) && all_finite(&t->scale_rel_per_c[0][0], 9) &&
           all_finite(&t->gyro_bias_rad_s_per_c[0][0], 9);
}

enum acal_error acal_decode(const uint8_t *blob, size_t len, struct acal_calibration *out) {
    struct reader r;
    size_t n;
    uint32_t stored;
    uint64_t unit, reference;
    uint16_t version;
    if (len < 12) {
        return ACAL_TOO_SHORT;
    }
    if (blob[0] != 'A' || blob[1] != 'C' || blob[2] != 'A' || blob[3] != 'L') {
        return ACAL_BAD_MAGIC;
    }
    version = (uint16_t)(blob[4] | (blob[5] << 8));
    if (version != ACAL_BLOB_VERSION && version != ACAL_BLOB_VERSION_1) {
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
    unit = take_variant(&r);
    out->output_unit = (uint8_t)unit;
    take_f64s(&r, out->zero_bias_out, 3);
    take_f64s(&r, out->scale_out_per_g, 3);
    take_f64s(&r, &out->installation_angles_deg[0][0], 9);
    take_f64s(&r, &out->lever_arms_m[0][0], 9);
    reference = take_variant(&r);
    out->reference = (uint8_t)reference;
    out->reference_offset_m[0] = out->reference_offset_m[1] = out->reference_offset_m[2] = 0.0;
    if (reference == 2) {
        take_f64s(&r, out->reference_offset_m, 3);
    }
    out->gravity_m_s2 = take_f64(&r);
    out->created_unix_s = take_varint(&r, 10, 0x01u);
    set_absent_sections(out);
    if (version == ACAL_BLOB_VERSION && r.ok) {
        take_sections(&r, out);
    }
    if (!r.ok || r.left != 0 || unit > 3 || reference > 2) {
        return ACAL_MALFORMED;
    }
    if (!all_finite(out->zero_bias_out, 3) || !all_finite(out->scale_out_per_g, 3) ||
        !all_finite(&out->installation_angles_deg[0][0], 9) ||
        !all_finite(&out->lever_arms_m[0][0], 9) || !all_finite(out->reference_offset_m, 3) ||
        !isfinite(out->gravity_m_s2) || !sections_finite(out)) {
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

void acal_correct_rate(const struct acal_compensator *c, const float w[3], float omega[3]) {
    if (!c->gyro_corrected) {
        omega[0] = w[0];
        omega[1] = w[1];
        omega[2] = w[2];
        return;
    }
    for (int r = 0; r < 3; r++) {
        const float *m = c->gyro_inv[r];
        omega[r] = c->gyro_offset_rad_s[r] + m[0] * w[0] + m[1] * w[1] + m[2] * w[2];
    }
}

/* c1 x + c2 x^2 + c3 x^3 (Horner), as the device evaluates it. */
static float poly_no_constant(const float k[3], float x) {
    return x * (k[0] + x * (k[1] + x * k[2]));
}

enum acal_temperature_state acal_refresh(struct acal_compensator *c, const struct acal_thermal *th,
                                         float temp_c) {
    float t, dt, b[3];
    if (!isfinite(temp_c)) {
        return ACAL_TEMPERATURE_NO_READING;
    }
    t = temp_c < th->range_c[0] ? th->range_c[0] : temp_c;
    t = t > th->range_c[1] ? th->range_c[1] : t;
    dt = t - th->reference_c;
    for (int i = 0; i < 3; i++) {
        const float gain = 1.0f + poly_no_constant(th->scale_poly[i], dt);
        const float inv_gain = 1.0f / gain;
        c->zero_bias_out[i] = th->zero_bias_out[i] + poly_no_constant(th->zero_bias_poly[i], dt);
        b[i] = th->gyro_bias_rad_s[i] + poly_no_constant(th->gyro_bias_poly[i], dt);
        for (int r = 0; r < 3; r++) {
            c->ka_m_s2_per_out[r][i] = th->ka_m_s2_per_out[r][i] * inv_gain;
            c->p[i][r] = th->p[i][r] * gain;
            c->q[i][r] = th->q[i][r] * gain;
        }
        c->s[i] = th->s[i] * gain;
    }
    for (int r = 0; r < 3; r++) {
        const float *m = c->gyro_inv[r];
        c->gyro_offset_rad_s[r] = -(m[0] * b[0] + m[1] * b[1] + m[2] * b[2]);
    }
    return t == temp_c ? ACAL_TEMPERATURE_IN_RANGE : ACAL_TEMPERATURE_CLAMPED;
}

/* See acal_device.h. */
#include "acal_device.h"

#include <math.h>

int acal_omega_dot_init(struct acal_omega_dot *e, float sample_rate_hz, float corner_hz) {
    const double pi = 3.14159265358979323846;
    if (!(isfinite(sample_rate_hz) && isfinite(corner_hz) && sample_rate_hz > 0.0f && corner_hz > 0.0f &&
          corner_hz < sample_rate_hz / 2.0f)) {
        return -1;
    }
    e->sample_rate_hz = sample_rate_hz;
    e->beta = (float)(1.0 - exp(-2.0 * pi * (double)corner_hz / (double)sample_rate_hz));
    acal_omega_dot_reset(e);
    for (int j = 0; j < 3; j++) {
        e->previous_rad_s[j] = 0.0f;
    }
    return 0;
}

void acal_omega_dot_update(struct acal_omega_dot *e, const float omega_rad_s[3], float omega_dot_rad_s2[3]) {
    if (!e->primed) {
        for (int j = 0; j < 3; j++) {
            e->previous_rad_s[j] = omega_rad_s[j];
        }
        e->primed = 1;
    }
    for (int j = 0; j < 3; j++) {
        const float x = (omega_rad_s[j] - e->previous_rad_s[j]) * e->sample_rate_hz;
        e->stage1[j] += e->beta * (x - e->stage1[j]);
        e->stage2[j] += e->beta * (e->stage1[j] - e->stage2[j]);
        e->previous_rad_s[j] = omega_rad_s[j];
        omega_dot_rad_s2[j] = e->stage2[j];
    }
}

void acal_omega_dot_reset(struct acal_omega_dot *e) {
    e->primed = 0;
    for (int j = 0; j < 3; j++) {
        e->stage1[j] = 0.0f;
        e->stage2[j] = 0.0f;
    }
}

int acal_device_init(struct acal_device *d, const struct acal_compensator *c,
                     const struct acal_thermal *th, float sample_rate_hz) {
    const double per_refresh = (double)sample_rate_hz / (double)ACAL_TEMPERATURE_REFRESH_HZ;
    d->c = *c;
    d->thermal = th;
    d->refresh_samples = per_refresh > 1.0 ? (uint32_t)per_refresh : 1u;
    d->since_refresh = 0;
    d->refreshed = 0;
    d->temperature_state = ACAL_TEMPERATURE_IN_RANGE;
    return acal_omega_dot_init(&d->omega_dot, sample_rate_hz,
                               sample_rate_hz * ACAL_OMEGA_DOT_CORNER_FRACTION);
}

enum acal_temperature_state acal_device_temperature(struct acal_device *d, float temp_c) {
    if (d->thermal != NULL && (!d->refreshed || d->since_refresh >= d->refresh_samples)) {
        d->temperature_state = acal_refresh(&d->c, d->thermal, temp_c);
        d->refreshed = 1;
        d->since_refresh = 0;
    }
    d->since_refresh++;
    return d->temperature_state;
}

static int all_finite(const float v[3]) {
    return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]);
}

int acal_device_sample(struct acal_device *d, const float u[3], const float w_rad_s[3],
                       float f_m_s2[3], float omega_rad_s[3]) {
    float omega[3], omega_dot[3];
    if (!all_finite(u) || !all_finite(w_rad_s)) {
        acal_omega_dot_reset(&d->omega_dot);
        return -1;
    }
    acal_correct_rate(&d->c, w_rad_s, omega);
    acal_omega_dot_update(&d->omega_dot, omega, omega_dot);
    acal_compensate(&d->c, u, omega, omega_dot, f_m_s2);
    for (int j = 0; j < 3; j++) {
        omega_rad_s[j] = omega[j];
    }
    return 0;
}

void acal_device_restart(struct acal_device *d) {
    acal_omega_dot_reset(&d->omega_dot);
}

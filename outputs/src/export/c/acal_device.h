/*
 * The device's whole per-sample correction for C firmware, on top of acal_blob.h: the gyro's output
 * corrected to the body rate (acal_correct_rate), the angular acceleration estimated from that rate
 * (two cascaded one-pole low-pass sections on the backward difference, docs/model.md 4.6), the
 * compensation with every lever-arm term (acal_compensate), and the temperature model refreshed at
 * most ACAL_TEMPERATURE_REFRESH_HZ times a second (acal_refresh). The order and the single-precision
 * operations are the Rust device's: compiled with -ffp-contract=off (no fused multiply-add) the
 * results equal `host apply`'s bit for bit.
 *
 * Use, with the constants of acal_calibration.h:
 *   struct acal_device dev;
 *   acal_device_init(&dev, &ACAL_COMPENSATOR, ACAL_THERMAL_OR_NULL, 1000.0f);
 *   per sample: [acal_device_temperature(&dev, temp_c);]  (a sample with a temperature reading)
 *               acal_device_sample(&dev, u, w_rad_s, f_m_s2, omega_rad_s);
 *   after a gap in the stream: acal_device_restart(&dev);
 */
#ifndef ACAL_DEVICE_H
#define ACAL_DEVICE_H

#include "acal_blob.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The estimator's corner frequency as a fraction of the sample rate (the firmware's). */
#define ACAL_OMEGA_DOT_CORNER_FRACTION 0.02f
/** Temperature refreshes per second at most (the firmware's). */
#define ACAL_TEMPERATURE_REFRESH_HZ 4u

/** The angular-acceleration estimator: x = fs (w_n - w_n-1), two one-pole sections of coefficient beta. */
struct acal_omega_dot {
    float sample_rate_hz;
    float beta;                       /* 1 - exp(-2 pi corner / fs) */
    float previous_rad_s[3];
    float stage1[3];
    float stage2[3];
    uint8_t primed;                   /* 0: the next sample only primes the difference */
};

/** 0, or -1 when not 0 < corner_hz < sample_rate_hz / 2 (both finite). */
int acal_omega_dot_init(struct acal_omega_dot *e, float sample_rate_hz, float corner_hz);

/** Feeds one (corrected) body rate, rad/s; writes the current estimate, rad/s^2. */
void acal_omega_dot_update(struct acal_omega_dot *e, const float omega_rad_s[3], float omega_dot_rad_s2[3]);

/** Restarts from no history. */
void acal_omega_dot_reset(struct acal_omega_dot *e);

/** One unit's per-sample state. */
struct acal_device {
    struct acal_compensator c;        /* the constants in force (refreshed with temperature) */
    const struct acal_thermal *thermal; /* NULL: no temperature model */
    struct acal_omega_dot omega_dot;
    uint32_t refresh_samples;         /* samples between two refreshes */
    uint32_t since_refresh;
    uint8_t refreshed;                /* 0: none yet (the first reading refreshes at once) */
    enum acal_temperature_state temperature_state;
};

/**
 * Starts from the constants c (copied) and, with a temperature model, th (kept by pointer: pass
 * &ACAL_THERMAL, or NULL without one), for samples at sample_rate_hz. 0, or -1 for a sample rate
 * the estimator cannot use.
 */
int acal_device_init(struct acal_device *d, const struct acal_compensator *c,
                     const struct acal_thermal *th, float sample_rate_hz);

/**
 * A temperature reading (deg C) that comes with the next sample: refreshes the constants when the
 * last refresh is at least sample_rate / ACAL_TEMPERATURE_REFRESH_HZ readings old. Returns the state
 * (in range, clamped to the model's valid range, or no reading); flag the samples when not in range.
 */
enum acal_temperature_state acal_device_temperature(struct acal_device *d, float temp_c);

/**
 * One sample: u in the output unit, w_rad_s the gyro's output. Writes the specific force at the
 * reference point (m/s^2, body axes) and the corrected body rate (rad/s). Returns 0, or -1 for a
 * sample with a non-finite value (outputs untouched, the estimate restarts).
 */
int acal_device_sample(struct acal_device *d, const float u[3], const float w_rad_s[3],
                       float f_m_s2[3], float omega_rad_s[3]);

/** After a gap in the stream: the angular-acceleration estimate restarts. */
void acal_device_restart(struct acal_device *d);

#ifdef __cplusplus
}
#endif

#endif /* ACAL_DEVICE_H */

/*
 * Example: check the calibration blob, correct one sample with the device's code, print it.
 * Copy the parts you need into your firmware.
 *
 * Build:  cc -std=c99 -ffp-contract=off example.c acal_blob.c acal_device.c -lm -o example
 * Run:    ./example [ux uy uz [wx wy wz [temp_c]]]
 *         u in the unit's output unit, w the gyro's output in rad/s, temp_c in deg C. Without
 *         arguments the sample is the unit at rest, z up (u = u0 + k_z on z, w = the gyro bias).
 */
#include <stdio.h>
#include <stdlib.h>
#include "acal_calibration.h"

int main(int argc, char **argv) {
    struct acal_calibration cal;
    struct acal_device dev;
    float u[3], w[3], f_m_s2[3], omega_rad_s[3];
    int i;

    /* 1. Decode the blob as the device would read it from its store (checks the CRC). */
    const enum acal_error rc = acal_decode(ACAL_BLOB, ACAL_BLOB_LEN, &cal);
    if (rc != ACAL_OK) {
        fprintf(stderr, "blob refused: acal_error %d\n", (int)rc);
        return 1;
    }
    printf("unit ");
    for (i = 0; i < 12; i++) printf("%02x", cal.unit_id[i]);
    printf(", gravity %.9g m/s^2, gyro %s, temperature model %s\n", cal.gravity_m_s2,
           cal.has_gyro ? "present" : "absent", cal.has_temperature ? "present" : "absent");

    /* 2. One sample: from the arguments, or the unit at rest with z up. */
    for (i = 0; i < 3; i++) {
        u[i] = (float)(cal.zero_bias_out[i] + (i == 2 ? cal.scale_out_per_g[2] : 0.0));
        w[i] = (float)cal.gyro.bias_rad_s[i];
    }
    for (i = 0; i < 3 && argc > 1 + i; i++) u[i] = strtof(argv[1 + i], NULL);
    for (i = 0; i < 3 && argc > 4 + i; i++) w[i] = strtof(argv[4 + i], NULL);

    /* 3. The device's per-sample correction, at 1000 samples a second. */
    if (acal_device_init(&dev, &ACAL_COMPENSATOR, ACAL_THERMAL_OR_NULL, 1000.0f) != 0) return 1;
    if (argc > 7) acal_device_temperature(&dev, strtof(argv[7], NULL));
    if (acal_device_sample(&dev, u, w, f_m_s2, omega_rad_s) != 0) {
        fprintf(stderr, "sample refused: a value is not finite\n");
        return 1;
    }

    /* 4. Print: specific force at the reference point and body rate, body axes. */
    printf("u %.9g %.9g %.9g\n", u[0], u[1], u[2]);
    printf("f_m_s2 %.9g %.9g %.9g\n", f_m_s2[0], f_m_s2[1], f_m_s2[2]);
    printf("omega_rad_s %.9g %.9g %.9g\n", omega_rad_s[0], omega_rad_s[1], omega_rad_s[2]);
    return 0;
}

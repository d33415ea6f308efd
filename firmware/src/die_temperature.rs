//! The STM32F4's on-chip temperature sensor: its ADC code to °C with the two factory calibration
//! points (reference manual RM0390 §13.10; datasheet "temperature sensor calibration values":
//! `TS_CAL1` at 30 °C and `TS_CAL2` at 110 °C, both taken with VDDA = 3.3 V).
//!
//! It measures the microcontroller's die, a proxy for the accelerometers' temperature on a small
//! board; a sensor inside the accelerometer package (or the gyro's) tracks them more closely and fits
//! the same [`crate::pipeline::Pipeline::set_temperature`] call.

/// Temperature of the first factory calibration point, °C.
pub const CAL1_C: f32 = 30.0;
/// Temperature of the second factory calibration point, °C.
pub const CAL2_C: f32 = 110.0;
/// Supply at which the calibration codes were taken, V.
pub const CAL_VDDA_V: f32 = 3.3;

/// °C from a 12-bit conversion `code` taken with supply `vdda_v`, and the factory codes `cal1`
/// (30 °C) and `cal2` (110 °C). NaN when the calibration codes are implausible (equal or reversed,
/// e.g. an erased or foreign part), so that the reading is left out rather than trusted. One division:
/// called a few times a second, never per sample.
pub fn from_code(code: u16, cal1: u16, cal2: u16, vdda_v: f32) -> f32 {
    if cal2 <= cal1 {
        return f32::NAN;
    }
    let at_cal_supply = f32::from(code) * (vdda_v / CAL_VDDA_V);
    CAL1_C + (CAL2_C - CAL1_C) * (at_cal_supply - f32::from(cal1)) / f32::from(cal2 - cal1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn calibration_points_and_midpoint() {
        // Typical F446 values: 0.76 V at 25 °C, 2.5 mV/°C → about 941 and 1189 codes at 30/110 °C.
        let (c1, c2) = (941, 1189);
        assert_eq!(from_code(c1, c1, c2, 3.3), 30.0);
        assert_eq!(from_code(c2, c1, c2, 3.3), 110.0);
        assert_eq!(from_code(1065, c1, c2, 3.3), 70.0);
        assert!(from_code(1000, 1000, 1000, 3.3).is_nan());
        assert!(from_code(1000, 1189, 941, 3.3).is_nan());
    }
}

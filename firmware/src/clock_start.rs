//! Starting an STM32 board's clock without hanging on a missing external clock.
//!
//! stm32f4xx-hal 0.23 turns the HSE on and waits for it with no bound (`Rcc::freeze`,
//! `src/rcc/f4/mod.rs:429-437`: `while rcc.cr().read().hserdy().bit_is_clear() {}`; its own doc
//! of `use_hse`: "Will result in a hang if an external oscillator is not connected or it fails to
//! start"). On a Nucleo-64 the 8 MHz on OSC_IN comes from the ST-LINK's MCO only where the board's
//! solder bridges route it (the board's user manual, "OSC clock"); a board without them spins
//! there forever, before any LED or log. ST's own HAL bounds the same wait by
//! `HSE_STARTUP_TIMEOUT`, 100 ms (`stm32f4xx_hal_conf_template.h`, read by `HAL_RCC_OscConfig`),
//! returning `HAL_TIMEOUT` instead of waiting on. This board code bounds it the same way: it turns
//! the HSE on, waits at most [`HSE_STARTUP_TIMEOUT_MS`] for HSERDY ([`settle`]), and otherwise
//! turns it off and runs the same PLL from the 16 MHz HSI (factory-trimmed to ±1 % at 25 °C:
//! enough for the bench's UART link; the sample clock is then off by as much), saying so in its
//! log.

/// The longest wait for HSERDY, ms (ST's `HSE_STARTUP_TIMEOUT`).
pub const HSE_STARTUP_TIMEOUT_MS: u32 = 100;

/// The clock the core runs from before the PLL: the HSI, Hz.
pub const HSI_HZ: u32 = 16_000_000;

/// Core cycles each poll waits at least (the board's poll calls `cortex_m::asm::delay` with it).
pub const CYCLES_PER_POLL: u32 = 16;

/// Polls of HSERDY within [`HSE_STARTUP_TIMEOUT_MS`] at the HSI's rate: each poll takes at least
/// [`CYCLES_PER_POLL`] cycles, so that the wait lasts at least the timeout and at most a few
/// times it.
pub const HSE_POLLS: u32 = HSE_STARTUP_TIMEOUT_MS * (HSI_HZ / 1000) / CYCLES_PER_POLL;

/// Where the system clock comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClockSource {
    /// The external clock (HSE) became ready.
    Hse,
    /// It did not within the bound: the internal RC oscillator (HSI).
    Hsi,
}

/// Asks `ready` (one poll of HSERDY, waiting [`CYCLES_PER_POLL`] cycles when not ready) at most
/// `polls` times: [`ClockSource::Hse`] at the first `true`, else [`ClockSource::Hsi`].
pub fn settle(mut ready: impl FnMut() -> bool, polls: u32) -> ClockSource {
    for _ in 0..polls {
        if ready() {
            return ClockSource::Hse;
        }
    }
    ClockSource::Hsi
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_clock_that_never_starts_falls_back_to_the_hsi_after_the_bound() {
        let mut asked = 0u32;
        let source = settle(
            || {
                asked += 1;
                false
            },
            HSE_POLLS,
        );
        assert_eq!(source, ClockSource::Hsi);
        assert_eq!(asked, HSE_POLLS);
        // At least the timeout at the HSI's rate, in cycles.
        let cycles = u64::from(HSE_POLLS) * u64::from(CYCLES_PER_POLL);
        assert!(cycles >= u64::from(HSE_STARTUP_TIMEOUT_MS) * u64::from(HSI_HZ) / 1000);
    }

    #[test]
    fn a_clock_ready_late_within_the_bound_is_taken() {
        let mut asked = 0u32;
        let source = settle(
            || {
                asked += 1;
                asked == HSE_POLLS
            },
            HSE_POLLS,
        );
        assert_eq!(source, ClockSource::Hse);
        assert_eq!(settle(|| true, HSE_POLLS), ClockSource::Hse);
    }
}

//! The register check of a part read by a DMA burst chain (`crate::imu_bursts`), PX4's
//! `RegisterCheck` pattern (`src/drivers/imu/invensense/icm42688p/ICM42688P.cpp`, `RegisterCheck`,
//! "reset" on a mismatch): a part that resets under the board (a brown-out on its supply) comes
//! back with every register at its reset value — PWR_MGMT0 0 (both sensors off), the FIFO in
//! bypass, INT1 not routed — so it raises no watermark, and the chain's stall restart alone would
//! flush its empty FIFO every 100 ms forever. After a stall, the board reads back the bank-0
//! registers the configuration wrote ([`checked_registers`]); where one differs, the part is
//! started again as at boot ([`check_and_heal`]).
//!
//! **Periodically**, as PX4 does it (`ICM42688P.cpp`, `RunImpl`, state FIFO_READ: "check
//! configuration registers periodically or immediately following any failure", `if (!success ||
//! hrt_elapsed_time(&_last_config_check_timestamp) > 100_ms)`, one register of each bank per check,
//! `_checked_register_bank0 = (_checked_register_bank0 + 1) % size_register_bank0_cfg`, `Reset()`
//! on a mismatch): [`RegisterCheck`] names one register at a time, round robin, and the burst chain
//! reads it between its FIFO reads every 100 ms (`crate::imu_bursts`, "The register check"). A
//! register changed while the FIFO keeps flowing — a flipped bit, a range changed by a glitch — is
//! invisible to the data path (the samples decode, only at the wrong scale); the stall check alone
//! never finds it. With the periodic check it is found within one round of the list, 100 ms per
//! register, and the part is started again ([`restart`]).

use embedded_hal::spi::{Operation, SpiDevice};

use super::regs::{Register, READ, SIGNAL_PATH_RESET};
use super::{configure_steps, Config, Core, Error, Icm42688, Step};

/// Registers the check reads back at most.
pub const MAX_CHECKED: usize = 24;

/// The bank-0 registers [`configure_steps`] writes, each with the last value written (bank 0 is
/// the one selected after the configuration and after a reset), less SIGNAL_PATH_RESET, whose
/// bits clear themselves, and the read-modify-write steps, whose other bits are the part's.
pub fn checked_registers(cfg: &Config) -> heapless::Vec<(u8, u8), MAX_CHECKED> {
    let mut out: heapless::Vec<(u8, u8), MAX_CHECKED> = heapless::Vec::new();
    for step in configure_steps(cfg) {
        let Step::Write(Register::Bank0(reg), value) = step else {
            continue;
        };
        if reg == SIGNAL_PATH_RESET {
            continue;
        }
        let reg = reg.addr();
        match out.iter_mut().find(|(r, _)| *r == reg) {
            Some(entry) => entry.1 = value,
            // At most one entry per register of the list: the list holds fewer than MAX_CHECKED.
            None => {
                let _ = out.push((reg, value));
            }
        }
    }
    out
}

/// One configured register at a time, round robin: PX4's `_checked_register_bank0` (module
/// documentation). The board reads [`Self::current`] when the bus is free and calls
/// [`Self::advance`] when it held its value; on a mismatch the part is started again and the same
/// register is read at the next check.
#[derive(Clone, Debug)]
pub struct RegisterCheck {
    regs: heapless::Vec<(u8, u8), MAX_CHECKED>,
    next: usize,
}

impl RegisterCheck {
    /// Over `cfg`'s [`checked_registers`], from the first.
    pub fn new(cfg: &Config) -> Self {
        RegisterCheck {
            regs: checked_registers(cfg),
            next: 0,
        }
    }

    /// The register to read next and the value it must hold (`None`: nothing to check).
    pub fn current(&self) -> Option<(u8, u8)> {
        self.regs.get(self.next).copied()
    }

    /// The current register held its value: the next one at the next check.
    pub fn advance(&mut self) {
        self.next = (self.next + 1) % self.regs.len().max(1);
    }

    /// Registers in one round.
    pub fn len(&self) -> usize {
        self.regs.len()
    }

    /// Nothing to check (a configuration that writes no bank-0 register; never the driver's).
    pub fn is_empty(&self) -> bool {
        self.regs.is_empty()
    }
}

/// Starts the part again as at boot (`Icm42688::new`: power-up wait, reset, identity,
/// configuration, FIFO flushed) and gives the burst reader's fresh state for it.
pub fn restart<SPI: SpiDevice>(spi: SPI, cfg: Config) -> Result<Core, Error<SPI::Error>> {
    Icm42688::new(spi, cfg)?;
    Core::new(cfg).map_err(Error::Config)
}

/// What the check found.
pub enum Checked {
    /// Every checked register holds its configured value.
    Intact,
    /// `reg` read `read`, not `expected`: the part was started again, and reading goes on with
    /// this fresh state.
    Restarted {
        /// The first register found changed.
        reg: u8,
        /// Its configured value.
        expected: u8,
        /// What it read.
        read: u8,
        /// The burst reader's new driver state.
        core: Core,
    },
}

/// Reads back `cfg`'s [`checked_registers`] over `spi`; at the first that differs, starts the part
/// again (`Icm42688::new`: power-up wait, reset, identity, configuration).
pub fn check_and_heal<SPI: SpiDevice>(
    mut spi: SPI,
    cfg: Config,
) -> Result<Checked, Error<SPI::Error>> {
    for (reg, expected) in checked_registers(&cfg) {
        let mut b = [0u8; 1];
        spi.transaction(&mut [Operation::Write(&[reg | READ]), Operation::Read(&mut b)])
            .map_err(Error::Spi)?;
        if b[0] != expected {
            let core = restart(&mut spi, cfg)?;
            return Ok(Checked::Restarted {
                reg,
                expected,
                read: b[0],
                core,
            });
        }
    }
    Ok(Checked::Intact)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::imu::icm42688::regs::{
        FIFO_CONFIG, FIFO_MODE_STOP_ON_FULL, GYRO_CONFIG_STATIC2, PWR_LOW_NOISE, PWR_MGMT0,
        REG_BANK_SEL,
    };

    #[test]
    fn the_checked_registers_are_bank_0_at_their_last_value() {
        let regs = checked_registers(&Config::DEFAULT);
        let value = |reg: u8| regs.iter().find(|(r, _)| *r == reg).map(|e| e.1);
        // Written twice (off, then low-noise; bypass, then stop-on-full): the last value counts.
        assert_eq!(value(PWR_MGMT0.addr()), Some(PWR_LOW_NOISE));
        assert_eq!(value(FIFO_CONFIG.addr()), Some(FIFO_MODE_STOP_ON_FULL));
        // A bank-1 register, the bank select and the self-clearing reset are not read back.
        assert_eq!(value(GYRO_CONFIG_STATIC2.addr()), None);
        assert_eq!(value(REG_BANK_SEL), None);
        assert_eq!(value(SIGNAL_PATH_RESET.addr()), None);
        assert!(regs.len() >= 10, "{}", regs.len());
    }

    #[test]
    fn the_round_robin_visits_every_checked_register_in_turn() {
        let regs = checked_registers(&Config::DEFAULT);
        let mut check = RegisterCheck::new(&Config::DEFAULT);
        assert_eq!(check.len(), regs.len());
        let mut seen = Vec::new();
        for _ in 0..2 * regs.len() {
            seen.push(check.current().expect("a register"));
            check.advance();
        }
        assert_eq!(&seen[..regs.len()], &regs[..]);
        assert_eq!(&seen[regs.len()..], &regs[..], "and again from the first");
    }
}

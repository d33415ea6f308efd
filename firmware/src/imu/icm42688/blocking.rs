//! The blocking form over `embedded_hal::spi::SpiDevice`: moves the bytes [`Core`] and the step
//! lists ask for.

use embedded_hal::spi::{Operation, SpiDevice};

use super::regs::*;
use super::self_test::{self, SelfTestReport, SensorUnderTest};
use super::{
    check_identity, configure_steps, Config, Core, Error, FifoBuffer, Step, BATCH_PACKETS,
    RESET_STEPS,
};
use crate::imu::{Drained, ImuSample, ImuSource};

/// ICM-42688-P on a blocking SPI device (mode 0 or 3, up to 24 MHz).
pub struct Icm42688<SPI> {
    spi: SPI,
    core: Core,
    buf: FifoBuffer,
}

impl<SPI: SpiDevice> Icm42688<SPI> {
    /// Resets the part, checks WHO_AM_I, configures it for `cfg` and starts the FIFO.
    pub fn new(spi: SPI, cfg: Config) -> Result<Self, Error<SPI::Error>> {
        let core = Core::new(cfg).map_err(Error::Config)?;
        let mut imu = Icm42688 {
            spi,
            core,
            buf: [0; BATCH_PACKETS * PACKET4_LEN],
        };
        imu.reset()?;
        check_identity(imu.who_am_i()?)?;
        imu.configure(cfg)?;
        Ok(imu)
    }

    /// Soft reset (every register to its reset value, the FIFO emptied), 1 ms.
    pub fn reset(&mut self) -> Result<(), Error<SPI::Error>> {
        self.run(&RESET_STEPS)
    }

    /// WHO_AM_I (0x47 for this part).
    pub fn who_am_i(&mut self) -> Result<u8, Error<SPI::Error>> {
        let mut v = [0u8; 1];
        self.read(WHO_AM_I, &mut v)?;
        Ok(v[0])
    }

    /// Applies a new configuration (sensors restarted, FIFO flushed: the next sample is flagged as
    /// following lost data).
    pub fn configure(&mut self, cfg: Config) -> Result<(), Error<SPI::Error>> {
        self.core = Core::new(cfg).map_err(Error::Config)?;
        self.run(&configure_steps(&cfg))
    }

    /// The configuration in force.
    pub fn config(&self) -> &Config {
        self.core.config()
    }

    /// Runs the self-test (about 0.7 s; the FIFO is restarted after it, and the next sample is
    /// flagged as following lost data) and reports each axis against the datasheet's limits.
    pub fn self_test(&mut self) -> Result<SelfTestReport, Error<SPI::Error>> {
        let saved = *self.core.config();
        let mut report = SelfTestReport::default();
        for sensor in [SensorUnderTest::Gyro, SensorUnderTest::Accel] {
            self.run(&self_test::enter_steps(sensor))?;
            let off = self.average(sensor)?;
            self.run(&self_test::enable_steps(sensor))?;
            let on = self.average(sensor)?;
            let mut codes = [0u8; 3];
            self.write(REG_BANK_SEL, sensor.code_bank())?;
            let read = self.read(sensor.code_register(), &mut codes);
            self.write(REG_BANK_SEL, 0)?;
            read?;
            report.set(sensor, off, on, codes);
        }
        self.configure(saved)?;
        self.core.corrupted();
        Ok(report)
    }

    fn average(&mut self, sensor: SensorUnderTest) -> Result<[i32; 3], Error<SPI::Error>> {
        let mut acc = self_test::Averager::default();
        for _ in 0..self_test::SAMPLES {
            let mut b = [0u8; 6];
            self.spi
                .transaction(&mut [
                    Operation::DelayNs(self_test::SAMPLE_WAIT_NS),
                    Operation::Write(&[sensor.data_register() | READ]),
                    Operation::Read(&mut b),
                ])
                .map_err(Error::Spi)?;
            acc.add(&b);
        }
        Ok(acc.mean())
    }

    fn run(&mut self, steps: &[Step]) -> Result<(), Error<SPI::Error>> {
        for s in steps {
            match *s {
                Step::Write(reg, v) => self.write(reg, v)?,
                Step::WaitUs(0) => {}
                Step::WaitUs(us) => self
                    .spi
                    .transaction(&mut [Operation::DelayNs(us.saturating_mul(1000))])
                    .map_err(Error::Spi)?,
            }
        }
        Ok(())
    }

    fn write(&mut self, reg: u8, v: u8) -> Result<(), Error<SPI::Error>> {
        self.spi.write(&[reg & !READ, v]).map_err(Error::Spi)
    }

    fn read(&mut self, reg: u8, buf: &mut [u8]) -> Result<(), Error<SPI::Error>> {
        self.spi
            .transaction(&mut [Operation::Write(&[reg | READ]), Operation::Read(buf)])
            .map_err(Error::Spi)
    }

    /// The SPI device (e.g. a simulated part's clock, or a shared bus's settings).
    pub fn device_mut(&mut self) -> &mut SPI {
        &mut self.spi
    }

    /// Gives the SPI device back.
    pub fn release(self) -> SPI {
        self.spi
    }
}

impl<SPI: SpiDevice> ImuSource for Icm42688<SPI> {
    type Error = Error<SPI::Error>;

    /// Reads INT_STATUS and the FIFO count in one burst (clearing the latched INT1), then up to
    /// `out.len()` (at most [`BATCH_PACKETS`]) packets in a second one, and decodes them.
    fn drain(&mut self, out: &mut [ImuSample]) -> Result<Drained, Self::Error> {
        let mut status = [0u8; 3];
        self.read(INT_STATUS, &mut status)?;
        let (bytes, more) = self.core.plan_read(status, out.len().min(BATCH_PACKETS));
        if bytes == 0 {
            return Ok(Drained { samples: 0, more });
        }
        let spi = &mut self.spi;
        spi.transaction(&mut [
            Operation::Write(&[FIFO_DATA | READ]),
            Operation::Read(&mut self.buf[..bytes]),
        ])
        .map_err(Error::Spi)?;
        match self.core.decode(&self.buf[..bytes], out) {
            Ok(samples) => Ok(Drained { samples, more }),
            Err(header) => {
                self.write(SIGNAL_PATH_RESET, FIFO_FLUSH)?;
                Err(Error::FifoCorrupt { header })
            }
        }
    }

    fn sample_rate_hz(&self) -> u32 {
        self.core.sample_rate_hz()
    }
}

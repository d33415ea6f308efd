//! The async form over `embedded_hal_async::spi::SpiDevice` (a DMA-driven SPI under an executor):
//! the blocking form's byte moves with `.await`; [`Core`] and the step lists decide everything.

use embedded_hal_async::spi::{Operation, SpiDevice};

use super::regs::*;
use super::self_test::{self, SelfTestReport, SensorUnderTest};
use super::{
    check_identity, configure_steps, Config, Core, Error, FifoBuffer, Step, BATCH_PACKETS,
    RESET_STEPS,
};
use crate::imu::{Drained, ImuSample, ImuSourceAsync};

/// ICM-42688-P on an async SPI device (mode 0 or 3, up to 24 MHz).
pub struct Icm42688Async<SPI> {
    spi: SPI,
    core: Core,
    buf: FifoBuffer,
}

impl<SPI: SpiDevice> Icm42688Async<SPI> {
    /// Resets the part, checks WHO_AM_I, configures it for `cfg` and starts the FIFO.
    pub async fn new(spi: SPI, cfg: Config) -> Result<Self, Error<SPI::Error>> {
        let core = Core::new(cfg).map_err(Error::Config)?;
        let mut imu = Icm42688Async {
            spi,
            core,
            buf: [0; BATCH_PACKETS * PACKET4_LEN],
        };
        imu.reset().await?;
        check_identity(imu.who_am_i().await?)?;
        imu.configure(cfg).await?;
        Ok(imu)
    }

    /// Soft reset (every register to its reset value, the FIFO emptied), 1 ms.
    pub async fn reset(&mut self) -> Result<(), Error<SPI::Error>> {
        self.run(&RESET_STEPS).await
    }

    /// WHO_AM_I (0x47 for this part).
    pub async fn who_am_i(&mut self) -> Result<u8, Error<SPI::Error>> {
        let mut v = [0u8; 1];
        self.read(WHO_AM_I, &mut v).await?;
        Ok(v[0])
    }

    /// Applies a new configuration (sensors restarted, FIFO flushed: the next sample is flagged as
    /// following lost data).
    pub async fn configure(&mut self, cfg: Config) -> Result<(), Error<SPI::Error>> {
        self.core = Core::new(cfg).map_err(Error::Config)?;
        self.run(&configure_steps(&cfg)).await
    }

    /// The configuration in force.
    pub fn config(&self) -> &Config {
        self.core.config()
    }

    /// Runs the self-test (about 0.7 s; the FIFO is restarted after it, and the next sample is
    /// flagged as following lost data) and reports each axis against the datasheet's limits.
    pub async fn self_test(&mut self) -> Result<SelfTestReport, Error<SPI::Error>> {
        let saved = *self.core.config();
        let mut report = SelfTestReport::default();
        for sensor in [SensorUnderTest::Gyro, SensorUnderTest::Accel] {
            self.run(&self_test::enter_steps(sensor)).await?;
            let off = self.average(sensor).await?;
            self.run(&self_test::enable_steps(sensor)).await?;
            let on = self.average(sensor).await?;
            let mut codes = [0u8; 3];
            self.write(REG_BANK_SEL, sensor.code_bank()).await?;
            let read = self.read(sensor.code_register(), &mut codes).await;
            self.write(REG_BANK_SEL, 0).await?;
            read?;
            report.set(sensor, off, on, codes);
        }
        self.configure(saved).await?;
        self.core.corrupted();
        Ok(report)
    }

    async fn average(&mut self, sensor: SensorUnderTest) -> Result<[i32; 3], Error<SPI::Error>> {
        let mut acc = self_test::Averager::default();
        for _ in 0..self_test::SAMPLES {
            let mut b = [0u8; 6];
            self.spi
                .transaction(&mut [
                    Operation::DelayNs(self_test::SAMPLE_WAIT_NS),
                    Operation::Write(&[sensor.data_register() | READ]),
                    Operation::Read(&mut b),
                ])
                .await
                .map_err(Error::Spi)?;
            acc.add(&b);
        }
        Ok(acc.mean())
    }

    async fn run(&mut self, steps: &[Step]) -> Result<(), Error<SPI::Error>> {
        for s in steps {
            match *s {
                Step::Write(reg, v) => self.write(reg, v).await?,
                Step::WaitUs(0) => {}
                Step::WaitUs(us) => self
                    .spi
                    .transaction(&mut [Operation::DelayNs(us.saturating_mul(1000))])
                    .await
                    .map_err(Error::Spi)?,
            }
        }
        Ok(())
    }

    async fn write(&mut self, reg: u8, v: u8) -> Result<(), Error<SPI::Error>> {
        self.spi.write(&[reg & !READ, v]).await.map_err(Error::Spi)
    }

    async fn read(&mut self, reg: u8, buf: &mut [u8]) -> Result<(), Error<SPI::Error>> {
        self.spi
            .transaction(&mut [Operation::Write(&[reg | READ]), Operation::Read(buf)])
            .await
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

impl<SPI: SpiDevice> ImuSourceAsync for Icm42688Async<SPI> {
    type Error = Error<SPI::Error>;

    /// Reads INT_STATUS and the FIFO count in one burst (clearing the latched INT1), then up to
    /// `out.len()` (at most [`BATCH_PACKETS`]) packets in a second one, and decodes them.
    async fn drain(&mut self, out: &mut [ImuSample]) -> Result<Drained, Self::Error> {
        let mut status = [0u8; 3];
        self.read(INT_STATUS, &mut status).await?;
        let (bytes, more) = self.core.plan_read(status, out.len().min(BATCH_PACKETS));
        if bytes == 0 {
            return Ok(Drained { samples: 0, more });
        }
        let spi = &mut self.spi;
        spi.transaction(&mut [
            Operation::Write(&[FIFO_DATA | READ]),
            Operation::Read(&mut self.buf[..bytes]),
        ])
        .await
        .map_err(Error::Spi)?;
        match self.core.decode(&self.buf[..bytes], out) {
            Ok(samples) => Ok(Drained { samples, more }),
            Err(header) => {
                self.write(SIGNAL_PATH_RESET, FIFO_FLUSH).await?;
                Err(Error::FifoCorrupt { header })
            }
        }
    }

    fn sample_rate_hz(&self) -> u32 {
        self.core.sample_rate_hz()
    }
}

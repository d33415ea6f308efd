//! The driver's text, written once for both forms: the blocking [`Icm42688`](super::Icm42688) and
//! the async [`Icm42688Async`](super::Icm42688Async) differ only in `async` and `.await`, so
//! `driver!` writes each from the one text below, given the form's SPI trait, its `ImuSource`
//! trait, the `async` keyword (or nothing) and the macro that completes an SPI call (`awaited!` or
//! `done!`). [`Core`](super::Core) and the step lists decide everything; this only moves bytes.

/// An SPI call as the blocking form makes it.
macro_rules! done {
    ($call:expr) => {
        $call
    };
}

/// An SPI call as the async form makes it.
macro_rules! awaited {
    ($call:expr) => {
        $call.await
    };
}

/// One form of the driver: `$name` over `$spi`, implementing `$source`; `$($async)?` and `$wait`
/// say how its SPI calls complete.
macro_rules! driver {
    (
        $(#[$doc:meta])*
        $name:ident, $spi:path, $source:ident, [$($async:ident)?], $wait:ident
    ) => {
        $(#[$doc])*
        pub struct $name<SPI> {
            spi: SPI,
            core: Core,
            buf: FifoBuffer,
        }

        impl<SPI: $spi> $name<SPI> {
            /// Waits out the part's power-on time, resets it, identifies it ([`Self::identify`]),
            /// configures it for `cfg` and starts the FIFO.
            pub $($async)? fn new(spi: SPI, cfg: Config) -> Result<Self, Error<SPI::Error>> {
                let core = Core::new(cfg).map_err(Error::Config)?;
                let mut imu = $name {
                    spi,
                    core,
                    buf: [0; BATCH_PACKETS * PACKET4_LEN],
                };
                $wait!(imu.run(&POWER_UP_STEPS, None))?;
                $wait!(imu.reset())?;
                $wait!(imu.identify())?;
                $wait!(imu.configure(cfg))?;
                Ok(imu)
            }

            /// Reads WHO_AM_I until it is 0x47, at most [`IDENTIFY_READS`] times
            /// [`IDENTIFY_RETRY_US`] apart; refuses the part with the last value read.
            pub $($async)? fn identify(&mut self) -> Result<(), Error<SPI::Error>> {
                let mut id = $wait!(self.who_am_i())?;
                for _ in 1..IDENTIFY_READS {
                    if id == WHO_AM_I_VALUE {
                        break;
                    }
                    $wait!(self.run(&[Step::WaitUs(IDENTIFY_RETRY_US)], None))?;
                    id = $wait!(self.who_am_i())?;
                }
                check_identity(id)
            }

            /// Soft reset (every register to its reset value, the FIFO emptied), 1 ms.
            pub $($async)? fn reset(&mut self) -> Result<(), Error<SPI::Error>> {
                $wait!(self.run(&RESET_STEPS, None))?;
                Ok(())
            }

            /// WHO_AM_I (0x47 for this part).
            pub $($async)? fn who_am_i(&mut self) -> Result<u8, Error<SPI::Error>> {
                let mut v = [0u8; 1];
                $wait!(self.read(WHO_AM_I, &mut v))?;
                Ok(v[0])
            }

            /// Applies a new configuration (sensors restarted, FIFO flushed: the next sample is
            /// flagged as following lost data).
            pub $($async)? fn configure(&mut self, cfg: Config) -> Result<(), Error<SPI::Error>> {
                self.core = Core::new(cfg).map_err(Error::Config)?;
                $wait!(self.run(&configure_steps(&cfg), None))?;
                Ok(())
            }

            /// The configuration in force.
            pub fn config(&self) -> &Config {
                self.core.config()
            }

            /// Runs the self-test with TDK's setting (`self_test`'s module doc; about 1.1 s; the
            /// FIFO is restarted after it, and the next sample is flagged as following lost data)
            /// and reports each axis against the datasheet's limits. `Error::NoDataReady` when the
            /// part stops flagging new samples.
            pub $($async)? fn self_test(&mut self) -> Result<SelfTestReport, Error<SPI::Error>> {
                let saved = *self.core.config();
                let mut filters = [0u8; 3];
                $wait!(self.read_banked(self_test::SAVED_FILTERS[0].reg(), &mut filters))?;
                let mut report = SelfTestReport::default();
                for sensor in [SensorUnderTest::Gyro, SensorUnderTest::Accel] {
                    let bank = $wait!(self.run(&self_test::enter_steps(sensor), None))?;
                    let off = $wait!(self.average(sensor))?;
                    // The averaging only reads: the bank the entry left is still selected.
                    $wait!(self.run(&self_test::enable_steps(sensor), bank))?;
                    let on = $wait!(self.average(sensor))?;
                    let mut codes = [0u8; 3];
                    $wait!(self.read_banked(sensor.code_register(), &mut codes))?;
                    report.set(sensor, off, on, codes);
                }
                $wait!(self.run(&self_test::restore_steps(filters), None))?;
                $wait!(self.configure(saved))?;
                self.core.corrupted();
                Ok(report)
            }

            $($async)? fn average(
                &mut self,
                sensor: SensorUnderTest,
            ) -> Result<[i32; 3], Error<SPI::Error>> {
                // A sample is read when INT_STATUS says DATA_RDY (the read clears it), never on
                // a timer: the part's clock is not the board's.
                let mut acc = self_test::Averager::default();
                let mut polls = 0;
                while acc.count() < self_test::SAMPLES {
                    if polls == self_test::MAX_POLLS {
                        return Err(Error::NoDataReady);
                    }
                    polls += 1;
                    let mut status = [0u8; 1];
                    $wait!(self.spi.transaction(&mut [
                        Operation::DelayNs(self_test::POLL_WAIT_NS),
                        Operation::Write(&[INT_STATUS as u8 | READ]),
                        Operation::Read(&mut status),
                    ]))
                    .map_err(Error::Spi)?;
                    if status[0] & INT_DATA_RDY != 0 {
                        let mut b = [0u8; 6];
                        $wait!(self.read(sensor.data_register(), &mut b))?;
                        acc.add(&b);
                    }
                }
                Ok(acc.mean())
            }

            /// Runs `steps` with `bank` selected (`None`: not known), writing REG_BANK_SEL before
            /// each register of another bank (§14.51); gives the bank it leaves selected.
            $($async)? fn run(
                &mut self,
                steps: &[Step],
                mut bank: Option<u8>,
            ) -> Result<Option<u8>, Error<SPI::Error>> {
                for s in steps {
                    if let Some(reg) = s.register() {
                        if bank != Some(reg.bank()) {
                            $wait!(self.write_addr(REG_BANK_SEL, reg.bank()))?;
                            bank = Some(reg.bank());
                        }
                    }
                    match *s {
                        Step::Write(reg, v) => $wait!(self.write_addr(reg.addr(), v))?,
                        Step::Update { reg, mask, value } => {
                            let mut v = [0u8; 1];
                            $wait!(self.read_addr(reg.addr(), &mut v))?;
                            $wait!(self.write_addr(reg.addr(), (v[0] & !mask) | (value & mask)))?
                        }
                        Step::WaitUs(0) => {}
                        Step::WaitUs(us) => $wait!(self
                            .spi
                            .transaction(&mut [Operation::DelayNs(us.saturating_mul(1000))]))
                        .map_err(Error::Spi)?,
                    }
                }
                Ok(bank)
            }

            /// Reads `buf.len()` registers from `reg` on in its bank: REG_BANK_SEL set to it, and
            /// back to bank 0 (the data path's) after a register of another bank, even when the
            /// read failed.
            $($async)? fn read_banked(
                &mut self,
                reg: Register,
                buf: &mut [u8],
            ) -> Result<(), Error<SPI::Error>> {
                $wait!(self.write_addr(REG_BANK_SEL, reg.bank()))?;
                let read = $wait!(self.read_addr(reg.addr(), buf));
                if reg.bank() != 0 {
                    $wait!(self.write_addr(REG_BANK_SEL, 0))?;
                }
                read
            }

            /// Writes a bank-0 register, bank 0 being selected (after a reset, a step list, and
            /// while the FIFO is read).
            $($async)? fn write(&mut self, reg: Bank0, v: u8) -> Result<(), Error<SPI::Error>> {
                $wait!(self.write_addr(reg.addr(), v))
            }

            /// Reads bank-0 registers from `reg` on, bank 0 being selected.
            $($async)? fn read(&mut self, reg: Bank0, buf: &mut [u8]) -> Result<(), Error<SPI::Error>> {
                $wait!(self.read_addr(reg.addr(), buf))
            }

            $($async)? fn write_addr(&mut self, addr: u8, v: u8) -> Result<(), Error<SPI::Error>> {
                $wait!(self.spi.write(&[addr & !READ, v])).map_err(Error::Spi)
            }

            $($async)? fn read_addr(
                &mut self,
                addr: u8,
                buf: &mut [u8],
            ) -> Result<(), Error<SPI::Error>> {
                $wait!(self
                    .spi
                    .transaction(&mut [Operation::Write(&[addr | READ]), Operation::Read(buf)]))
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

        impl<SPI: $spi> $source for $name<SPI> {
            type Error = Error<SPI::Error>;

            /// Reads INT_STATUS and the FIFO count in one burst (clearing the latched INT1), then up
            /// to `out.len()` (at most [`BATCH_PACKETS`]) packets in a second one, and decodes them.
            $($async)? fn drain(&mut self, out: &mut [ImuSample]) -> Result<Drained, Self::Error> {
                let mut status = [0u8; 3];
                $wait!(self.read(INT_STATUS, &mut status))?;
                let (bytes, more) = self.core.plan_read(status, out.len().min(BATCH_PACKETS));
                if bytes == 0 {
                    return Ok(Drained { samples: 0, more });
                }
                let spi = &mut self.spi;
                $wait!(spi.transaction(&mut [
                    Operation::Write(&[FIFO_DATA as u8 | READ]),
                    Operation::Read(&mut self.buf[..bytes]),
                ]))
                .map_err(Error::Spi)?;
                match self.core.decode(&self.buf[..bytes], out) {
                    Ok(samples) => Ok(Drained { samples, more }),
                    Err(header) => {
                        $wait!(self.write(SIGNAL_PATH_RESET, FIFO_FLUSH))?;
                        Err(Error::FifoCorrupt { header })
                    }
                }
            }

            fn sample_rate_hz(&self) -> u32 {
                self.core.sample_rate_hz()
            }
        }
    };
}

pub(super) use {awaited, done, driver};

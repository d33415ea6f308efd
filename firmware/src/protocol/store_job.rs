//! A calibration write on its way to the flash, handed from the request handler to the board's
//! lowest priority.
//!
//! Why: erasing a store slot (a 16 KiB STM32F4 sector) takes 250 ms typical, 500 ms at most
//! (`crate::flash_layout`, from DS8626's "Flash memory programming") and programming the record a
//! few milliseconds (16 µs a word). On the F405 the request
//! handler runs in the USB interrupt; a store there would hold that interrupt for the whole erase.
//! So the handler only validates the blob and parks it here with the store itself
//! ([`super::LinkService::take_store_job`]), owes the host its answer, and reads no further
//! request; the board's idle loop (F405) or main loop (QEMU, the simulated device) calls
//! [`StoreJob::run`], outside any interrupt and any lock, and hands the job back
//! ([`super::LinkService::finish_store`]), which applies the calibration and answers. The job owns
//! the store while it is away, so nothing else can touch the flash meanwhile.

use shared::blob::BLOB_MAX_LEN;

use crate::storage::{CalStore, StoreError};

/// The store and the validated blob to write, and, once run, how it went.
pub struct StoreJob<S> {
    pub(super) store: S,
    pub(super) blob: [u8; BLOB_MAX_LEN],
    pub(super) len: usize,
    pub(super) result: Option<Result<(), StoreError>>,
}

impl<S: CalStore> StoreJob<S> {
    /// Erases (when the slot is not blank) and programs the record: the slow part. Call it from the
    /// board's lowest priority, never from an interrupt. Running it twice stores once.
    pub fn run(&mut self) {
        if self.result.is_none() {
            self.result = Some(self.store.store(&self.blob[..self.len]));
        }
    }

    /// [`Self::run`] has been called.
    pub fn is_done(&self) -> bool {
        self.result.is_some()
    }
}

/// Where a board parks a job between the link's interrupt and its idle loop: posted by the link
/// (not yet run), taken by the idle loop, posted back run, taken back by the link.
pub struct StoreMailbox<S> {
    slot: Option<StoreJob<S>>,
}

impl<S: CalStore> Default for StoreMailbox<S> {
    fn default() -> Self {
        Self::new()
    }
}

impl<S: CalStore> StoreMailbox<S> {
    /// Empty.
    pub const fn new() -> Self {
        StoreMailbox { slot: None }
    }

    /// Parks a job (a job already parked is never replaced: the link owes one answer at a time).
    pub fn post(&mut self, job: StoreJob<S>) {
        if self.slot.is_none() {
            self.slot = Some(job);
        }
    }

    /// A job still to run (for the idle loop).
    pub fn take_to_run(&mut self) -> Option<StoreJob<S>> {
        self.slot.take_if(|j| !j.is_done())
    }

    /// A job that has run (for the link).
    pub fn take_done(&mut self) -> Option<StoreJob<S>> {
        self.slot.take_if(|j| j.is_done())
    }
}

//! ST LSM6DSO driver (in progress).

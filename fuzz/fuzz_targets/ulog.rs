#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| host::fuzz::Target::Ulog.fuzz_one(data));

//! cargo-fuzz target `state`: see `fuzz/harness.rs`.
#![no_main]

#[path = "../harness.rs"]
mod harness;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    // libfuzzer-sys's panic hook aborts on every panic, even one caught: the state
    // reader catches arrow-ipc's panics on malformed batches (see `render::state`),
    // so the default hook is put back. A panic that escapes still aborts (it cannot
    // unwind into libFuzzer) and is reported as a crash.
    static HOOK: std::sync::Once = std::sync::Once::new();
    HOOK.call_once(|| drop(std::panic::take_hook()));
    let _accepted = harness::state(data);
});

//! Fuzz target: the exact-number parser behind `--input LINK=SPEED`, spec
//! speeds and ratios written as text. It must answer quickly for any text
//! (the size bound), and what it accepts must print back to the same value.
#![no_main]

use egt_core::numerics::exact;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(q) = exact::parse_rational(text) {
        let back = exact::parse_rational(&exact::display(&q));
        assert_eq!(back, Ok(q), "display/parse round trip of {text:?}");
    }
});

//! Any text: parsing a dataset config (`weft data generate --config`) and validating it
//! never panics and holds at most `linear_bound` bytes while it reads; a config that
//! validates writes back to TOML that parses to the same config.
#![no_main]

use libfuzzer_sys::fuzz_target;
use weft_data::config::DataConfig;
use weft_fuzz::{bounded, linear_bound};

fuzz_target!(|data: &[u8]| {
    // The reader refuses anything but UTF-8 before parsing (read_input_to_string).
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let (read, _) = bounded(data.len(), linear_bound(data.len()), || {
        let config = DataConfig::from_toml(text)?;
        config.validate()?;
        Ok::<_, weft_data::DataError>(config)
    });
    let config = match read {
        Ok(c) => c,
        Err(e) => {
            let _ = e.to_string();
            return;
        }
    };
    let written = config.to_toml().expect("a valid config writes");
    let back = DataConfig::from_toml(&written).expect("a written config parses");
    assert_eq!(back, config, "{written}");
});

//! Fuzz target: the adjacency form (`adjacency = "1-2:a 1-3:G=-2/3 ..."`), the
//! bytes being the adjacency string under a fixed frame, through validation
//! and kinematics with the first DOF links driven at unit speed.
#![no_main]

use egt_core::solve::kinematics::SpeedInput;
use egt_core::{Format, Train};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(adjacency) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(adjacency) = serde_json::to_string(adjacency) else {
        return;
    };
    let text = format!("{{\"frame\": \"1\", \"adjacency\": {adjacency}}}");
    let Ok(train) = Train::from_str(&text, Format::Json, "fuzz") else {
        return;
    };
    let inputs: Vec<SpeedInput> = train
        .coordinates()
        .iter()
        .take(train.dof())
        .map(|&l| SpeedInput::from((l, 1.0)))
        .collect();
    if let Ok(speeds) = train.kinematics(&inputs) {
        for (s, known) in speeds.speed.iter().zip(&speeds.known) {
            assert!(!known || s.is_finite(), "accepted a non-finite speed");
        }
    }
});

//! Not library API: the speed/accuracy study and the generated train families
//! that the benchmarks, the `speed_accuracy` example and the core's tests share.
//! Each of those includes this folder with `#[path = ".../lab/mod.rs"] mod lab;`.

#![allow(dead_code)]

pub mod accuracy;
pub mod families;

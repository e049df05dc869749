//! Shared by the property-test files (`mod common;`).

use proptest::test_runner::{Config, RngSeed};

/// Proptest configuration: `default_cases` per property with a fixed seed (reproducible CI);
/// with `NLRT_EXTENSIVE=1`, `extensive_cases` with a random seed (new inputs each run).
/// `PROPTEST_CASES` overrides the default count.
pub fn proptest_config(default_cases: u32, extensive_cases: u32) -> Config {
    let extensive = std::env::var_os("NLRT_EXTENSIVE").is_some();
    let cases = if extensive {
        extensive_cases
    } else {
        std::env::var("PROPTEST_CASES")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(default_cases)
    };
    let rng_seed = if extensive {
        RngSeed::Random
    } else {
        RngSeed::Fixed(0x6e6c_7274)
    };
    Config {
        cases,
        failure_persistence: None,
        rng_seed,
        ..Config::default()
    }
}

//! The example estimator config that ships in `systemd/` parses, holds the
//! defaults, and names every key (so it documents all of them).

use slope_pipeline::EstimatorConfig;

const EXAMPLE: &str = include_str!("../../../systemd/estimator.toml");

#[test]
fn the_example_config_is_the_defaults_with_every_key() {
    let parsed = EstimatorConfig::from_toml_str(EXAMPLE).expect("the example parses");
    assert_eq!(parsed, EstimatorConfig::default());
    let defaults = toml::to_string(&EstimatorConfig::default()).expect("serialises");
    let mut section = String::new();
    for line in defaults.lines().map(str::trim).filter(|l| !l.is_empty()) {
        if line.starts_with('[') {
            section = line.to_string();
            assert!(
                EXAMPLE.lines().any(|l| l.starts_with(&section)),
                "{section} missing"
            );
            continue;
        }
        let key = line.split(" = ").next().expect("key = value");
        assert!(
            EXAMPLE
                .lines()
                .any(|l| l.trim_start().starts_with(&format!("{key} "))),
            "{section} {key} is not in systemd/estimator.toml"
        );
    }
}

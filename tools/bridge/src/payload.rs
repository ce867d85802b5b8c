//! The JSON the bridge puts on Zenoh. Each message is one JSON object: the
//! key `schema` names its version, the other keys are those of
//! `slope-echo --json` (estimates), `slope-echo --surfaces --json`
//! (surfaces) and `slope-echo --health --json` (health reports). A reader checks `schema` first; a new field keeps the
//! version, a changed or removed one makes a new version.

use serde::Serialize;
use slope_ipc_types::{Health, SlopeEstimate, Surfaces};
use slope_tools::echo::{EstimateJson, HealthJson};
use slope_tools::surfaces_json::SurfacesJson;

/// `schema` of an estimate on `<prefix>/estimate`.
pub const ESTIMATE_SCHEMA: &str = "slope.estimate.json/1";
/// `schema` of a frame's surfaces on `<prefix>/surfaces` (the MCAP
/// channel's too).
pub const SURFACES_SCHEMA: &str = "slope.surfaces.json/1";
/// `schema` of a health report on `<prefix>/health`.
pub const HEALTH_SCHEMA: &str = "slope.health.json/1";

/// Suffix of the estimate key expression (`<key prefix>/estimate`).
pub const ESTIMATE_KEY: &str = "estimate";
/// Suffix of the surfaces key expression (`<key prefix>/surfaces`).
pub const SURFACES_KEY: &str = "surfaces";
/// Suffix of the health key expression (`<key prefix>/health`).
pub const HEALTH_KEY: &str = "health";

#[derive(Serialize)]
struct Versioned<T: Serialize> {
    schema: &'static str,
    #[serde(flatten)]
    body: T,
}

/// The JSON of an estimate.
pub fn estimate_json(estimate: &SlopeEstimate) -> serde_json::Result<String> {
    serde_json::to_string(&Versioned {
        schema: ESTIMATE_SCHEMA,
        body: EstimateJson::from(estimate),
    })
}

/// The JSON of a frame's surfaces.
pub fn surfaces_json(surfaces: &Surfaces) -> serde_json::Result<String> {
    serde_json::to_string(&Versioned {
        schema: SURFACES_SCHEMA,
        body: SurfacesJson::from(surfaces),
    })
}

/// The JSON of a health report.
pub fn health_json(health: &Health) -> serde_json::Result<String> {
    serde_json::to_string(&Versioned {
        schema: HEALTH_SCHEMA,
        body: HealthJson::from(health),
    })
}

#[cfg(test)]
mod tests {
    use serde_json::Value;
    use slope_ipc_types::{EstimateStatus, HealthComponent, TimingStats};

    use super::*;

    #[test]
    fn an_estimate_is_versioned_echo_json() {
        let estimate = SlopeEstimate {
            frame_index: 7,
            status: EstimateStatus::Ok as u32,
            slope_deg: 16.0,
            ..SlopeEstimate::default()
        };
        let value: Value = serde_json::from_str(&estimate_json(&estimate).unwrap()).unwrap();
        let echo = serde_json::to_value(EstimateJson::from(&estimate)).unwrap();
        assert_eq!(value["schema"], ESTIMATE_SCHEMA);
        // Every key of slope-echo --json, with its value, plus the schema.
        let object = value.as_object().unwrap();
        assert_eq!(object.len(), echo.as_object().unwrap().len() + 1);
        for (key, expected) in echo.as_object().unwrap() {
            assert_eq!(&object[key], expected, "{key}");
        }
        assert_eq!(value["frame"], 7);
        assert_eq!(value["slope_deg"], 16.0);
        assert!(value["distance_m"].is_null());
    }

    #[test]
    fn surfaces_are_versioned_echo_json() {
        let mut surfaces = Surfaces {
            frame_index: 9,
            count: 1,
            road: 0,
            ..Surfaces::default()
        };
        surfaces.surfaces[0].slope_deg = 16.0;
        let value: Value = serde_json::from_str(&surfaces_json(&surfaces).unwrap()).unwrap();
        let echo = serde_json::to_value(SurfacesJson::from(&surfaces)).unwrap();
        assert_eq!(value["schema"], SURFACES_SCHEMA);
        let object = value.as_object().unwrap();
        assert_eq!(object.len(), echo.as_object().unwrap().len() + 1);
        for (key, expected) in echo.as_object().unwrap() {
            assert_eq!(&object[key], expected, "{key}");
        }
        assert_eq!(value["surfaces"][0]["road"], true);
        assert_eq!(value["surfaces"][0]["slope_deg"], 16.0);
    }

    #[test]
    fn a_health_report_is_versioned_echo_json() {
        let mut health = Health::new(HealthComponent::Estimator);
        health.frames_out = 3;
        health.push_stage("total", TimingStats::of(&mut [1.0, 2.0, 3.0]));
        let value: Value = serde_json::from_str(&health_json(&health).unwrap()).unwrap();
        assert_eq!(value["schema"], HEALTH_SCHEMA);
        assert_eq!(value["component"], "estimator");
        assert_eq!(value["frames_out"], 3);
        assert_eq!(value["stages"][0]["median_ms"], 2.0);
    }
}

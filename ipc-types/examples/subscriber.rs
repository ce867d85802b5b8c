//! A planner's subscriber with bare iceoryx2: the code of the README's
//! "Subscribing from your own planner", compiled with the workspace.
//!
//! ```sh
//! cargo run -p slope-ipc-types --example subscriber              # prefix "slope" or $SLOPE_SERVICE_PREFIX
//! ```
//!
//! It opens `<prefix>/estimate` (retrying until slope-estimator has
//! created it) and prints every trusted estimate until Ctrl-C.

use std::time::Duration;

use iceoryx2::prelude::*;
use slope_ipc_types::{EstimateStatus, ServiceNames, SlopeEstimate};

const CYCLE_TIME: Duration = Duration::from_millis(10);

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let names = ServiceNames::from_env();
    let node = NodeBuilder::new().create::<ipc::Service>()?;
    let name: ServiceName = names.estimate().as_str().try_into()?;
    // Open, never create: the estimator creates the service with its
    // settings. It fails until slope-estimator has started: retry.
    let service = loop {
        match node
            .service_builder(&name)
            .publish_subscribe::<SlopeEstimate>()
            .open()
        {
            Ok(service) => break service,
            Err(_) if node.wait(Duration::from_millis(500)).is_ok() => continue,
            Err(err) => return Err(err.into()),
        }
    };
    let subscriber = service.subscriber_builder().create()?;
    // `node.wait` sleeps and returns an error on SIGINT/SIGTERM.
    while node.wait(CYCLE_TIME).is_ok() {
        while let Some(sample) = subscriber.receive()? {
            let e: &SlopeEstimate = sample.payload();
            if e.status() == EstimateStatus::Ok && e.confidence >= 0.5 {
                // e.slope_deg (this frame), e.tracked_slope_deg (over frames;
                // NaN without a track), e.distance_m, e.confidence_reason_names() ...
                println!(
                    "frame {}: {:+.2} deg, tracked {:+.2} deg",
                    e.frame_index, e.slope_deg, e.tracked_slope_deg
                );
            }
        }
    }
    Ok(())
}

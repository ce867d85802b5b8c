//! What every slope binary shares: service-prefix and verbosity flags,
//! logging set-up, and SIGINT/SIGTERM handling.

use std::io::IsTerminal;

use clap::Args;
use slope_ipc_types::{ServiceNames, DEFAULT_SERVICE_PREFIX, SERVICE_PREFIX_ENV};
use slope_sensor::publish::StopFlag;
use tracing_subscriber::EnvFilter;

/// Flags every daemon and client takes.
#[derive(Debug, Clone, Args)]
pub struct CommonArgs {
    /// Prefix of the iceoryx2 service names (`<prefix>/cloud`,
    /// `<prefix>/estimate`). Processes talk to each other only when they
    /// share it; tests use a unique one each.
    #[arg(long, env = SERVICE_PREFIX_ENV, default_value = DEFAULT_SERVICE_PREFIX, global = true)]
    pub service_prefix: String,

    /// More log output (-v debug, -vv trace). RUST_LOG overrides.
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    pub verbose: u8,

    /// Less log output (errors only).
    #[arg(short, long, global = true, conflicts_with = "verbose")]
    pub quiet: bool,
}

impl CommonArgs {
    pub fn service_names(&self) -> ServiceNames {
        ServiceNames::new(self.service_prefix.clone())
    }

    /// Sets up `tracing` to stderr (stdout stays free for results).
    pub fn init_logging(&self) {
        let level = match (self.quiet, self.verbose) {
            (true, _) => "error",
            (false, 0) => "info",
            (false, 1) => "debug",
            (false, _) => "trace",
        };
        let filter = EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new(level));
        // A second initialisation (only possible in tests) keeps the first.
        let _ = tracing_subscriber::fmt()
            .with_env_filter(filter)
            .with_writer(std::io::stderr)
            .with_ansi(std::io::stderr().is_terminal())
            .with_target(false)
            .try_init();
        // iceoryx2 logs through its own logger; keep it to real problems.
        iceoryx2::prelude::set_log_level(iceoryx2::prelude::LogLevel::Error);
    }
}

/// Installs the SIGINT/SIGTERM handler and returns the flag it sets.
pub fn stop_on_signals() -> anyhow::Result<StopFlag> {
    let stop = StopFlag::new();
    let handler_flag = stop.clone();
    ctrlc::set_handler(move || {
        if handler_flag.is_stopped() {
            // A second signal while shutting down: the user means it.
            std::process::exit(130);
        }
        handler_flag.stop();
    })
    .map_err(|e| anyhow::anyhow!("failed to install the SIGINT/SIGTERM handler: {e}"))?;
    Ok(stop)
}

/// A node name for this process: `<program>-<pid>`.
pub fn node_name(program: &str) -> String {
    format!("{program}-{}", std::process::id())
}

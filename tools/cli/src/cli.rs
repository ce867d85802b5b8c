//! What every slope binary shares: service-prefix and verbosity flags,
//! logging set-up, and SIGINT/SIGTERM handling.

use std::io::IsTerminal;
use std::path::Path;

use clap::Args;
use slope_ipc_types::{ServiceNames, DEFAULT_SERVICE_PREFIX, SERVICE_PREFIX_ENV};

use crate::config_file::{
    config_path, is_config_error, SlopeFile, DEFAULT_CONFIG_PATH, EXIT_CONFIG,
};
use slope_sensor::interruptible::run_interruptible;
use slope_sensor::publish::{StopFlag, StopRequest, StopSignals};
use slope_sensor::recording::Recording;
use tracing_subscriber::EnvFilter;

/// `-v`/`-q`: every program takes them, with the same meaning.
#[derive(Debug, Clone, Copy, Default, Args)]
pub struct LogArgs {
    /// More log output (-v debug, -vv trace). RUST_LOG overrides.
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    pub verbose: u8,

    /// Less log output (errors only).
    #[arg(short, long, global = true, conflicts_with = "verbose")]
    pub quiet: bool,
}

impl LogArgs {
    /// Sets up `tracing` to stderr (stdout stays free for results), in
    /// colour only when stderr is a terminal.
    pub fn init_logging(&self) {
        self.init_logging_quieting(&[]);
    }

    /// [`Self::init_logging`] with the log of the crates `noisy` (a
    /// library's own chatter, e.g. RustDDS's) off by default, its errors
    /// at `-v`, everything at `-vv`. RUST_LOG overrides.
    pub fn init_logging_quieting(&self, noisy: &[&str]) {
        let level = match (self.quiet, self.verbose) {
            (true, _) => "error",
            (false, 0) => "info",
            (false, 1) => "debug",
            (false, _) => "trace",
        };
        let noisy_level = match (self.quiet, self.verbose) {
            (false, 1) => "error",
            (false, 2..) => level,
            _ => "off",
        };
        let mut directives = level.to_string();
        for name in noisy {
            directives.push_str(&format!(",{name}={noisy_level}"));
        }
        let filter =
            EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new(&directives));
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

/// Flags every daemon and client takes.
#[derive(Debug, Clone, Args)]
pub struct CommonArgs {
    /// Prefix of the iceoryx2 service names (`<prefix>/cloud`,
    /// `<prefix>/estimate`). Processes talk to each other only when they
    /// share it; tests use a unique one each. Default: the environment
    /// variable SLOPE_SERVICE_PREFIX, else `service_prefix` of the config
    /// file (--config, else /etc/slope/slope.toml if it exists), else "slope".
    // Not clap's `env`: clap counts a value from the environment as given
    // on the command line and prints it in the usage line of every error
    // (`Usage: slope-replay --service-prefix <SERVICE_PREFIX> <RECORDING>`)
    // as if it were required. A default is not printed there, and is
    // checked by `prefix_arg` all the same.
    #[arg(
        long,
        global = true,
        value_parser = prefix_arg,
        default_value = prefix_from_env(),
        hide_default_value = true
    )]
    pub service_prefix: Option<String>,

    #[command(flatten)]
    pub log: LogArgs,
}

/// [`SERVICE_PREFIX_ENV`], read once, as the default of `--service-prefix`.
fn prefix_from_env() -> Option<&'static str> {
    static PREFIX: std::sync::OnceLock<Option<String>> = std::sync::OnceLock::new();
    PREFIX
        .get_or_init(|| std::env::var(SERVICE_PREFIX_ENV).ok())
        .as_deref()
}

/// `--service-prefix` of the clients without --config (`slope-echo`,
/// `slope-record`).
pub const CLIENT_PREFIX_HELP: &str = "Prefix of the iceoryx2 service names (`<prefix>/cloud`, \
`<prefix>/estimate`). Processes talk to each other only when they share it; tests use a unique \
one each. Default: the environment variable SLOPE_SERVICE_PREFIX, else `service_prefix` of \
/etc/slope/slope.toml (the daemons' config file) if it exists, else \"slope\"";

impl CommonArgs {
    /// A client's service names (`slope-echo`, `slope-record`): the prefix
    /// of `--service-prefix` (or its environment variable), else the
    /// daemons' `service_prefix` in /etc/slope/slope.toml when that file
    /// exists, else "slope"; so a client started by hand finds the daemons
    /// the file configures. A file that cannot be read is an error, and so
    /// is a stop request while it is read ([`read_settings`]).
    pub fn service_names(&self, stop: &StopFlag) -> anyhow::Result<ServiceNames> {
        self.service_names_from(Path::new(DEFAULT_CONFIG_PATH), stop)
    }

    /// [`Self::service_names`] with `default` for /etc/slope/slope.toml.
    pub fn service_names_from(
        &self,
        default: &Path,
        stop: &StopFlag,
    ) -> anyhow::Result<ServiceNames> {
        if let Some(prefix) = &self.service_prefix {
            return Ok(ServiceNames::new(prefix.clone()));
        }
        let file = read_settings(config_path(None, default).as_deref(), stop)?;
        Ok(ServiceNames::new(file.service_prefix))
    }

    /// `--service-prefix` (or its environment variable), else `fallback`
    /// (a config file's).
    pub fn prefix_or(&self, fallback: &str) -> String {
        self.service_prefix
            .clone()
            .unwrap_or_else(|| fallback.to_string())
    }

    pub fn init_logging(&self) {
        self.log.init_logging();
    }
}

/// A program that takes its output as `-o PATH` (or, as before, without
/// the flag): parsing fails with the usage error (status 2) that says what
/// is missing and how to give it ([`Self::OUTPUT_MISSING`]), where clap's
/// own message for a required group would name it `<--output <FILE>|OUTPUT>`.
pub trait OutputArgs: clap::Parser {
    /// What a command line without an output is told.
    const OUTPUT_MISSING: &'static str;

    /// The output given as `-o PATH`, and the one given without the flag.
    fn outputs(&self) -> (Option<&Path>, Option<&Path>);

    /// The command line, or the usage error that ends the program: clap's,
    /// or [`Self::OUTPUT_MISSING`].
    fn parse_checked() -> Self {
        Self::try_parse_checked_from(std::env::args_os()).unwrap_or_else(|err| err.exit())
    }

    /// [`clap::Parser::try_parse_from`], and [`Self::OUTPUT_MISSING`] when
    /// neither `-o PATH` nor PATH was given.
    fn try_parse_checked_from<I, T>(args: I) -> Result<Self, clap::Error>
    where
        I: IntoIterator<Item = T>,
        T: Into<std::ffi::OsString> + Clone,
    {
        let args = Self::try_parse_from(args)?;
        match args.outputs() {
            (None, None) => Err(Self::command().error(
                clap::error::ErrorKind::MissingRequiredArgument,
                Self::OUTPUT_MISSING,
            )),
            _ => Ok(args),
        }
    }
}

/// Opens the recording in `path` to read its frames (`slope-eval`,
/// `slope-convert`, `slope-replay`): refuses a `[depth]` size of more than
/// `max_points` points (`--max-points`) before any cloud is allocated, and
/// a recording without frames. The files are read on a thread of their
/// own: a stop request ends the wait for an open or a read that blocks (a
/// stalled network mount) with an error that says so.
pub fn open_recording(
    path: &Path,
    max_points: usize,
    stop: &StopFlag,
) -> anyhow::Result<Recording> {
    let dir = path.to_path_buf();
    let opened = run_interruptible("open-recording", stop, OPEN_SLICE, &mut || {}, move || {
        Recording::open(&dir)
    })?;
    let Some(recording) = opened else {
        anyhow::bail!("stopped before its files could be read (a stop request came first)");
    };
    let recording = recording?;
    recording
        .check_points(max_points)
        .map_err(|err| anyhow::anyhow!("{err} (--max-points)"))?;
    if recording.frames().is_empty() {
        anyhow::bail!("its frames.csv lists no frames");
    }
    Ok(recording)
}

/// The config file `path` (the defaults for `None`), read on a thread of
/// its own ([`SlopeFile::load_or_stop`]): a stop request while it is read
/// (a stalled network mount) is an error that says so.
pub fn read_settings(path: Option<&Path>, stop: &StopFlag) -> anyhow::Result<SlopeFile> {
    SlopeFile::load_or_stop(path, stop)?.ok_or_else(|| {
        anyhow::anyhow!("stopped before the config file could be read (a stop request came first)")
    })
}

/// How often a wait for a blocked open looks at the stop request.
const OPEN_SLICE: std::time::Duration = std::time::Duration::from_millis(50);

/// What `--max-frames 0` (and `--count 0`) answers, in every program.
pub const MAX_FRAMES_ZERO: &str = "must be at least 1 (leave the flag out for no limit)";

/// `--max-frames` (and its likes): at least 1; no flag, no limit. The same
/// rule in every program.
pub fn max_frames_arg(text: &str) -> Result<u64, String> {
    count_arg(text, MAX_FRAMES_ZERO)
}

/// A whole number of at least 1; 0 is answered with `zero` (what the flag's
/// 0 would have meant and what to do instead).
pub fn count_arg(text: &str, zero: &str) -> Result<u64, String> {
    match text.parse::<u64>() {
        Ok(0) => Err(zero.to_string()),
        Ok(n) => Ok(n),
        Err(_) => Err(format!("'{text}' is not a whole number")),
    }
}

/// The longest service prefix, in bytes: iceoryx2's longest service name
/// less the longest `/<suffix>` the prefix gets (`/estimate`), so that
/// every service name made from it is valid.
pub fn max_prefix_len() -> usize {
    let suffixes = ServiceNames::new(String::new());
    let longest_suffix = [suffixes.cloud(), suffixes.estimate(), suffixes.health()]
        .iter()
        .map(String::len)
        .max()
        .unwrap_or(0);
    iceoryx2::constants::MAX_SERVICE_NAME_LENGTH.saturating_sub(longest_suffix)
}

/// A service prefix: non-empty, at most [`max_prefix_len`] bytes,
/// printable ASCII, without surrounding slashes.
pub fn prefix_arg(text: &str) -> Result<String, String> {
    if text.is_empty() {
        return Err(format!(
            "the service prefix is empty (check {SERVICE_PREFIX_ENV}); the default is '{DEFAULT_SERVICE_PREFIX}'"
        ));
    }
    let max = max_prefix_len();
    if text.len() > max {
        return Err(format!(
            "the service prefix is {} bytes long; it may have at most {max} (iceoryx2's service \
             names have at most {} bytes, and the prefix gets /estimate added)",
            text.len(),
            iceoryx2::constants::MAX_SERVICE_NAME_LENGTH
        ));
    }
    if text.starts_with('/') || text.ends_with('/') || text.chars().any(char::is_control) {
        return Err(format!(
            "'{text}' is not a usable service prefix: no leading or trailing '/', no control characters"
        ));
    }
    // iceoryx2 takes ASCII service names only ("InvalidContent" otherwise)
    // and keeps `iox2://` for its own.
    if !text.is_ascii() || text.starts_with("iox2://") {
        return Err(format!(
            "'{text}' is not a usable service prefix: iceoryx2 service names are ASCII only \
             (letters, digits, punctuation) and may not start with iox2://"
        ));
    }
    Ok(text.to_string())
}

/// A note in the log when a topic stays silent: after `after` without data,
/// once, naming the service (its prefix included) and what should publish
/// on it; again after data came and went.
#[derive(Debug)]
pub struct SilenceNote {
    what: &'static str,
    service: String,
    publisher: &'static str,
    after: std::time::Duration,
    last_heard: std::time::Instant,
    noted: bool,
}

/// How long a topic may stay silent before its note.
pub const SILENCE_NOTE_AFTER: std::time::Duration = std::time::Duration::from_secs(5);

impl SilenceNote {
    /// `what` arrives on `service` from `publisher` (a program's name).
    pub fn new(what: &'static str, service: &str, publisher: &'static str) -> Self {
        Self {
            what,
            service: service.to_string(),
            publisher,
            after: SILENCE_NOTE_AFTER,
            last_heard: std::time::Instant::now(),
            noted: false,
        }
    }

    /// Data arrived.
    pub fn heard(&mut self) {
        self.last_heard = std::time::Instant::now();
        self.noted = false;
    }

    /// Called on every wake: logs the note once the silence is long enough.
    pub fn tick(&mut self) {
        let silent = self.last_heard.elapsed();
        if !self.noted && silent >= self.after {
            self.noted = true;
            tracing::info!(
                "no {} for {} s on service {}: is {} running with the same service prefix?",
                self.what,
                silent.as_secs(),
                self.service,
                self.publisher
            );
        }
    }
}

/// The exit status of a program's `run`, with its error (if any) printed
/// once on stderr: the error, then one line per cause. Never a backtrace,
/// whatever `RUST_BACKTRACE` says: a failed command is a user's problem to
/// read, not a bug (panics keep their backtraces).
pub fn exit_status(result: anyhow::Result<()>) -> std::process::ExitCode {
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("{}", error_report(&err));
            std::process::ExitCode::FAILURE
        }
    }
}

/// [`exit_status`] for a daemon that reads the config file: a config-file
/// error exits with [`EXIT_CONFIG`] (78), which its unit does not restart.
pub fn daemon_exit_status(result: anyhow::Result<()>) -> std::process::ExitCode {
    let config = result.as_ref().err().is_some_and(is_config_error);
    let status = exit_status(result);
    if config {
        std::process::ExitCode::from(EXIT_CONFIG)
    } else {
        status
    }
}

/// `error: ...` and a `caused by: ...` line per cause.
pub fn error_report(err: &anyhow::Error) -> String {
    let mut text = format!("error: {err}");
    for cause in err.chain().skip(1) {
        text.push_str(&format!("\n  caused by: {cause}"));
    }
    text
}

/// Installs the SIGINT/SIGTERM handler and returns the flag it sets. The
/// first signal sets the flag (and says so in the log); a second one ends
/// the program at once with status 130, after removing the temporary files
/// of unfinished outputs ([`crate::unfinished_files`]). A signal repeated
/// within 50 ms is the same request ([`StopSignals`]: `timeout`
/// sends two).
pub fn stop_on_signals() -> anyhow::Result<StopFlag> {
    write_errors_instead_of_sigxfsz()?;
    let stop = StopFlag::new();
    let handler_flag = stop.clone();
    let mut signals = StopSignals::new();
    ctrlc::set_handler(move || match signals.note(std::time::Instant::now()) {
        // A second signal while shutting down: the user means it. No
        // temporary file of an unfinished output stays behind.
        StopRequest::Second => crate::unfinished_files::remove_all_and_exit(130),
        StopRequest::Repeat => {}
        StopRequest::First => {
            tracing::info!("stopping; a second SIGINT/SIGTERM ends the program at once");
            handler_flag.stop();
        }
    })
    .map_err(|e| anyhow::anyhow!("failed to install the SIGINT/SIGTERM handler: {e}"))?;
    Ok(stop)
}

/// Blocks SIGXFSZ in this thread and every thread it starts from now on
/// (call it before any): a write past the file-size limit (`ulimit -f`)
/// then fails with EFBIG ("File too large"), which the program reports and
/// cleans up after (no `.part` left, an MCAP file's frames said), instead
/// of the signal killing it without a word (exit 153). The signal stays
/// pending, never delivered.
pub fn write_errors_instead_of_sigxfsz() -> anyhow::Result<()> {
    use nix::sys::signal::{SigSet, Signal};
    SigSet::from(Signal::SIGXFSZ)
        .thread_block()
        .map_err(|e| anyhow::anyhow!("cannot block SIGXFSZ: {e}"))
}

/// A node name for this process: `<program>-<pid>`.
pub fn node_name(program: &str) -> String {
    format!("{program}-{}", std::process::id())
}

/// How often a waiting loop wakes without data, to look at the stop flag
/// and at anything a missed notification would have left waiting.
pub const WAKE_INTERVAL: std::time::Duration = std::time::Duration::from_millis(100);

/// Sleeps in an iceoryx2 `WaitSet` on `listener` and calls `on_wake` after
/// every notification and every [`WAKE_INTERVAL`], until `on_wake` returns
/// `Ok(false)`, fails, or `stop` is set. `on_wake` should take everything
/// waiting: it is called on the interval too, so data whose notification
/// was missed is still seen.
pub fn wait_loop(
    listener: &slope_sensor::ipc::TopicListener,
    stop: &StopFlag,
    mut on_wake: impl FnMut() -> anyhow::Result<bool>,
) -> anyhow::Result<()> {
    use iceoryx2::prelude::{ipc, CallbackProgression, SignalHandlingMode, WaitSetBuilder};
    use iceoryx2::waitset::WaitSetRunResult;

    let waitset = WaitSetBuilder::new()
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<ipc::Service>()
        .map_err(|e| anyhow::anyhow!("failed to create the wait set: {e:?}"))?;
    let _data = waitset
        .attach_notification(listener.listener())
        .map_err(|e| anyhow::anyhow!("failed to attach the listener: {e:?}"))?;
    let _tick = waitset
        .attach_interval(WAKE_INTERVAL)
        .map_err(|e| anyhow::anyhow!("failed to attach the wake interval: {e:?}"))?;
    let mut failure: Option<anyhow::Error> = None;
    let mut on_event = |_| {
        let result = listener
            .drain()
            .map_err(anyhow::Error::from)
            .and_then(|_| on_wake());
        match result {
            Ok(true) if !stop.is_stopped() => CallbackProgression::Continue,
            Ok(_) => CallbackProgression::Stop,
            Err(err) => {
                failure = Some(err);
                CallbackProgression::Stop
            }
        }
    };
    loop {
        // A signal may interrupt the wait itself; the stop flag decides.
        match waitset.wait_and_process(&mut on_event) {
            Ok(WaitSetRunResult::StopRequest) => break,
            Ok(_) if stop.is_stopped() => break,
            Ok(_) => continue,
            Err(err) => return Err(anyhow::anyhow!("waiting for data failed: {err:?}")),
        }
    }
    match failure {
        Some(err) => Err(err),
        None => Ok(()),
    }
}

/// How far a run over frames got before SIGINT/SIGTERM stopped it
/// (`slope-eval`, `slope-convert`): "interrupted after N of M frames".
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Interruption {
    /// Frames handled (evaluated, or written or skipped as bad).
    pub frames_done: usize,
    /// Frames the run was asked to handle.
    pub frames_total: usize,
}

impl std::fmt::Display for Interruption {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "interrupted after {} of {} frames",
            self.frames_done, self.frames_total
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn common(prefix: Option<&str>) -> CommonArgs {
        CommonArgs {
            service_prefix: prefix.map(str::to_string),
            log: LogArgs::default(),
        }
    }

    /// Every prefix the parser takes makes service names iceoryx2 takes
    /// (each printable ASCII character tried), and a non-ASCII one, which
    /// iceoryx2 refuses ("InvalidContent"), is refused by the parser and
    /// by the config file (`--print-config` passed it).
    #[test]
    fn a_prefix_is_ascii_as_iceoryx2_service_names_are() {
        use iceoryx2::prelude::ServiceName;
        for c in (0x20u8..0x7f).map(char::from).filter(|&c| c != '/') {
            let prefix = format!("p{c}q");
            let names = ServiceNames::new(prefix_arg(&prefix).expect("printable ASCII"));
            for name in [names.cloud(), names.estimate(), names.health()] {
                assert!(ServiceName::new(&name).is_ok(), "{name:?}");
            }
        }
        for prefix in ["probe\u{e9}", "robot\u{2764}", "iox2://x"] {
            let names = ServiceNames::new(prefix.to_string());
            assert!(ServiceName::new(&names.cloud()).is_err(), "{prefix}");
            let err = prefix_arg(prefix).expect_err("not for iceoryx2");
            assert!(err.contains("ASCII only"), "{err}");
            let file = SlopeFile::from_toml_str(&format!("service_prefix = {prefix:?}\n"));
            assert!(file.is_err(), "{prefix}");
        }
    }

    /// The longest prefix makes valid service names; one byte more is
    /// refused by the parser, naming the limit.
    #[test]
    fn a_too_long_prefix_is_refused_with_the_limit() {
        let max = max_prefix_len();
        assert!(max > 200, "{max}");
        let longest = "p".repeat(max);
        let names = ServiceNames::new(prefix_arg(&longest).expect("fits"));
        for name in [names.cloud(), names.estimate(), names.health()] {
            iceoryx2::prelude::ServiceName::new(&name).expect("a valid service name");
        }
        let err = prefix_arg(&"p".repeat(max + 1)).expect_err("too long");
        assert!(err.contains(&format!("at most {max}")), "{err}");
        let err = prefix_arg(&"p".repeat(300)).expect_err("too long");
        assert!(err.contains("300 bytes"), "{err}");
    }

    #[test]
    fn a_client_takes_the_flag_else_the_daemons_file_else_the_default() {
        let dir = tempfile::tempdir().expect("temp dir");
        let file = dir.path().join("slope.toml");
        let missing = dir.path().join("missing.toml");
        // No file: the default prefix.
        let names = common(None)
            .service_names_from(&missing, &StopFlag::new())
            .expect("names");
        assert_eq!(names.prefix(), DEFAULT_SERVICE_PREFIX);
        // The file's prefix, unless the flag gives one.
        std::fs::write(&file, "service_prefix = \"robot7\"\n").expect("write");
        let names = common(None)
            .service_names_from(&file, &StopFlag::new())
            .expect("names");
        assert_eq!(names.prefix(), "robot7");
        let names = common(Some("lab"))
            .service_names_from(&file, &StopFlag::new())
            .expect("names");
        assert_eq!(names.prefix(), "lab");
        // A broken file is an error that names it, not a silent default.
        std::fs::write(&file, "service_prefx = \"robot7\"\n").expect("write");
        let e = common(None)
            .service_names_from(&file, &StopFlag::new())
            .unwrap_err();
        let report = error_report(&e);
        assert!(report.contains("slope.toml"), "{report}");
        assert!(report.contains("service_prefx"), "{report}");
    }
}

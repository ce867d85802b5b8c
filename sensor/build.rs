//! Build script of `slope-sensor`.
//!
//! Without the `kinect2` feature it does nothing: the default build needs no
//! SDK. With it, it finds libfreenect2 (the `FREENECT2_PREFIX` environment
//! variable, else pkg-config's `freenect2`), compiles the `extern "C"` shim in
//! `shim/` with the `cc` crate and generates Rust bindings for the shim's
//! header with bindgen into `$OUT_DIR/freenect2_shim.rs`. It never touches the
//! network.
//!
//! It reruns when the shim changes and when libfreenect2 is reinstalled: it
//! watches libfreenect2's `config.h` (which pipelines the shim compiles in)
//! and its library file (see `build_support/freenect2_files.rs`).

fn main() {
    #[cfg(feature = "kinect2")]
    kinect2::build();
}

#[cfg(feature = "kinect2")]
#[path = "build_support/freenect2_files.rs"]
// `pipelines_in_config_h` is for the tests (tests/build_script.rs).
#[allow(dead_code)]
mod freenect2_files;

#[cfg(feature = "kinect2")]
mod kinect2 {
    use std::path::{Path, PathBuf};

    use super::freenect2_files::watched_files;

    /// Overrides pkg-config: libfreenect2's install prefix (with `include/`
    /// and `lib/` below it).
    const PREFIX_ENV: &str = "FREENECT2_PREFIX";
    const SHIM_HEADER: &str = "shim/freenect2_shim.h";
    const SHIM_SOURCE: &str = "shim/freenect2_shim.cpp";

    /// Where libfreenect2's headers and library are.
    struct Freenect2Paths {
        include_dirs: Vec<PathBuf>,
        lib_dirs: Vec<PathBuf>,
    }

    pub fn build() {
        println!("cargo:rerun-if-changed={SHIM_HEADER}");
        println!("cargo:rerun-if-changed={SHIM_SOURCE}");
        println!("cargo:rerun-if-env-changed={PREFIX_ENV}");

        let paths = match find_freenect2() {
            Ok(paths) => paths,
            Err(reason) => fail(&reason),
        };
        watch_installed(&paths);

        let mut shim = cc::Build::new();
        shim.cpp(true)
            .file(SHIM_SOURCE)
            .include("shim")
            .flag_if_supported("-std=c++11")
            .warnings(true);
        for dir in &paths.include_dirs {
            shim.include(dir);
        }
        if let Err(err) = shim.try_compile("slope_freenect2_shim") {
            fail(&format!(
                "compiling {SHIM_SOURCE} against libfreenect2 (headers in {:?}) failed: {err}",
                paths.include_dirs
            ));
        }
        // The shim is a static library that needs libfreenect2: name it again
        // after the shim so that the linker resolves the shim's references.
        println!("cargo:rustc-link-lib=freenect2");

        let out_dir = match std::env::var("OUT_DIR") {
            Ok(dir) => PathBuf::from(dir),
            Err(_) => fail("cargo did not set OUT_DIR"),
        };
        let bindings = bindgen::Builder::default()
            .header(SHIM_HEADER)
            .allowlist_function("f2s_.*")
            .allowlist_type("f2s_.*")
            .allowlist_var("F2S_.*")
            // Values that come back from C must never be an invalid Rust enum.
            .newtype_enum("f2s_.*")
            .prepend_enum_name(false)
            .derive_default(true)
            .derive_debug(true)
            .parse_callbacks(Box::new(bindgen::CargoCallbacks::new()))
            .generate();
        let bindings = match bindings {
            Ok(bindings) => bindings,
            Err(err) => fail(&format!(
                "bindgen could not parse {SHIM_HEADER}: {err}. bindgen needs libclang \
                 (Debian/Ubuntu: `apt-get install libclang-dev`; or set LIBCLANG_PATH)"
            )),
        };
        if let Err(err) = bindings.write_to_file(out_dir.join("freenect2_shim.rs")) {
            fail(&format!(
                "writing the bindings into {}: {err}",
                out_dir.display()
            ));
        }
    }

    fn find_freenect2() -> Result<Freenect2Paths, String> {
        if let Some(prefix) = std::env::var_os(PREFIX_ENV).filter(|p| !p.is_empty()) {
            let prefix = PathBuf::from(prefix);
            return from_prefix(&prefix);
        }
        let library = pkg_config::Config::new()
            .atleast_version("0.2")
            // We name libfreenect2 ourselves after the shim (see above).
            .cargo_metadata(false)
            .probe("freenect2")
            .map_err(|err| {
                // pkg-config's own report is long; keep its gist.
                let detail = err.to_string();
                let gist = detail
                    .lines()
                    .map(str::trim)
                    .find(|line| line.contains("not found") || line.contains("version"))
                    .unwrap_or("pkg-config failed")
                    .to_string();
                format!(
                    "libfreenect2 (pkg-config package `freenect2` >= 0.2) was not found: {gist}\n\
                     Install libfreenect2 from its upstream source \
                     (github.com/OpenKinect/libfreenect2; see README \"Running on the robot\"), then\n\
                     - point pkg-config at it: PKG_CONFIG_PATH=<prefix>/lib/pkgconfig, or\n\
                     - set {PREFIX_ENV}=<prefix> (the directory holding include/libfreenect2 and lib/).\n\
                     To build without the Kinect v2, leave out `--features kinect2`."
                )
            })?;
        for dir in &library.link_paths {
            println!("cargo:rustc-link-search=native={}", dir.display());
        }
        Ok(Freenect2Paths {
            include_dirs: library.include_paths,
            lib_dirs: library.link_paths,
        })
    }

    fn from_prefix(prefix: &Path) -> Result<Freenect2Paths, String> {
        let include = prefix.join("include");
        if !include
            .join("libfreenect2")
            .join("libfreenect2.hpp")
            .is_file()
        {
            return Err(format!(
                "{PREFIX_ENV}={} has no include/libfreenect2/libfreenect2.hpp; \
                 set it to the prefix libfreenect2 was installed into \
                 (CMAKE_INSTALL_PREFIX), or unset it to use pkg-config.\n\
                 To build without the Kinect v2, leave out `--features kinect2`.",
                prefix.display()
            ));
        }
        let lib_dir = ["lib", "lib64"]
            .iter()
            .map(|dir| prefix.join(dir))
            .find(|dir| dir.join("libfreenect2.so").exists() || dir.join("libfreenect2.a").exists())
            .ok_or_else(|| {
                format!(
                    "{PREFIX_ENV}={} has no lib/libfreenect2.so; was libfreenect2 installed there?",
                    prefix.display()
                )
            })?;
        println!("cargo:rustc-link-search=native={}", lib_dir.display());
        Ok(Freenect2Paths {
            include_dirs: vec![include],
            lib_dirs: vec![lib_dir],
        })
    }

    /// Reruns the build script when libfreenect2's `config.h` or library
    /// changes (a reinstall with other pipelines), and tells the crate's
    /// tests which `config.h` the shim was compiled against.
    fn watch_installed(paths: &Freenect2Paths) {
        let watched = watched_files(&paths.include_dirs, &paths.lib_dirs);
        for file in &watched {
            println!("cargo:rerun-if-changed={}", file.display());
        }
        match watched.iter().find(|f| f.ends_with("config.h")) {
            Some(config_h) => {
                println!(
                    "cargo:rustc-env=SLOPE_FREENECT2_CONFIG_H={}",
                    config_h.display()
                )
            }
            None => println!(
                "cargo:warning=libfreenect2/config.h not found under {:?}; the shim will not be \
                 rebuilt when libfreenect2 is reinstalled (run `cargo clean -p slope-sensor` then)",
                paths.include_dirs
            ),
        }
        if !watched.iter().any(|f| !f.ends_with("config.h")) {
            println!(
                "cargo:warning=libfreenect2's library not found under {:?}; the shim will not be \
                 rebuilt when libfreenect2 is reinstalled",
                paths.lib_dirs
            );
        }
    }

    /// Stops the build with a message that says what to do.
    fn fail(reason: &str) -> ! {
        for line in reason.lines() {
            println!("cargo::error={line}");
        }
        std::process::exit(1);
    }
}

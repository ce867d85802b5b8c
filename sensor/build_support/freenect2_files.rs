//! Which files of an installed libfreenect2 the shim depends on, so that
//! `build.rs` recompiles the shim when libfreenect2 is reinstalled.
//!
//! The shim decides which depth pipelines exist when it compiles, from the
//! `LIBFREENECT2_WITH_*_SUPPORT` defines of libfreenect2's `config.h`, and it
//! references the classes of exactly those pipelines. A libfreenect2 rebuilt
//! with more pipelines would otherwise go unnoticed until `cargo clean`, and
//! one with fewer would leave undefined symbols at load time. So the build
//! script watches `config.h` and the library file (`cargo:rerun-if-changed`).
//!
//! Pure path logic, shared by `build.rs` and `tests/build_script.rs`
//! (included in both with `#[path]`).

use std::path::{Path, PathBuf};

/// Where compilers look when pkg-config reports no directory (it leaves out
/// the system ones).
pub const SYSTEM_INCLUDE_DIRS: [&str; 2] = ["/usr/local/include", "/usr/include"];
/// As above, for the library.
pub const SYSTEM_LIB_DIRS: [&str; 5] = [
    "/usr/local/lib",
    "/usr/local/lib64",
    "/usr/lib/x86_64-linux-gnu",
    "/usr/lib/aarch64-linux-gnu",
    "/usr/lib",
];

/// The library names a `-lfreenect2` link can resolve to.
const LIBRARY_FILES: [&str; 2] = ["libfreenect2.so", "libfreenect2.a"];

/// The files to watch: the first `libfreenect2/config.h` under
/// `include_dirs` (then the system include directories) and the first
/// library file under `lib_dirs` (then the system library directories).
/// Missing files are left out; the caller warns about them.
pub fn watched_files(include_dirs: &[PathBuf], lib_dirs: &[PathBuf]) -> Vec<PathBuf> {
    let system_includes: Vec<PathBuf> = SYSTEM_INCLUDE_DIRS.iter().map(PathBuf::from).collect();
    let system_libs: Vec<PathBuf> = SYSTEM_LIB_DIRS.iter().map(PathBuf::from).collect();
    let config_h = include_dirs
        .iter()
        .chain(&system_includes)
        .map(|dir| config_h_in(dir))
        .find(|path| path.is_file());
    let library = lib_dirs
        .iter()
        .chain(&system_libs)
        .flat_map(|dir| LIBRARY_FILES.iter().map(move |name| dir.join(name)))
        .find(|path| path.exists());
    config_h.into_iter().chain(library).collect()
}

/// `<include_dir>/libfreenect2/config.h`.
pub fn config_h_in(include_dir: &Path) -> PathBuf {
    include_dir.join("libfreenect2").join("config.h")
}

/// The pipeline names (as `slope-capture --pipeline` spells them) that a
/// `config.h` enables, besides `cpu` which is always built in.
pub fn pipelines_in_config_h(text: &str) -> Vec<&'static str> {
    let defined = |name: &str| {
        text.lines().any(|line| {
            let mut words = line.split_whitespace();
            matches!(
                (words.next(), words.next()),
                (Some("#define"), Some(word)) if word == name
            )
        })
    };
    let mut pipelines = vec!["cpu"];
    if defined("LIBFREENECT2_WITH_OPENCL_SUPPORT") {
        pipelines.extend(["cl", "clkde"]);
    }
    if defined("LIBFREENECT2_WITH_CUDA_SUPPORT") {
        pipelines.extend(["cuda", "cudakde"]);
    }
    if defined("LIBFREENECT2_WITH_OPENGL_SUPPORT") {
        pipelines.push("gl");
    }
    pipelines
}

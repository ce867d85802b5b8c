//! The build script's choice of libfreenect2 files to watch (issue #13,
//! item 1): a reinstalled libfreenect2 must rebuild the shim. The path
//! logic runs without libfreenect2; with the `kinect2` feature the shim is
//! also checked against the `config.h` it was compiled with.

#[path = "../build_support/freenect2_files.rs"]
#[allow(dead_code)]
mod freenect2_files;

use std::path::{Path, PathBuf};

use freenect2_files::{pipelines_in_config_h, watched_files};

fn touch(path: &Path) {
    std::fs::create_dir_all(path.parent().expect("a parent")).expect("mkdir");
    std::fs::write(path, b"").expect("write");
}

#[test]
fn config_h_and_the_library_of_the_prefix_are_watched() {
    let prefix = tempfile::tempdir().expect("temp dir");
    let include = prefix.path().join("include");
    let lib = prefix.path().join("lib");
    touch(&include.join("libfreenect2/config.h"));
    touch(&lib.join("libfreenect2.so.0.2.0"));
    std::os::unix::fs::symlink("libfreenect2.so.0.2.0", lib.join("libfreenect2.so"))
        .expect("symlink");
    let watched = watched_files(std::slice::from_ref(&include), std::slice::from_ref(&lib));
    assert_eq!(
        watched,
        vec![
            include.join("libfreenect2/config.h"),
            lib.join("libfreenect2.so")
        ]
    );
}

#[test]
fn a_static_library_is_watched_and_missing_files_are_left_out() {
    let prefix = tempfile::tempdir().expect("temp dir");
    let include: PathBuf = prefix.path().join("nowhere/include");
    let lib = prefix.path().join("lib");
    touch(&lib.join("libfreenect2.a"));
    let watched = watched_files(&[include], std::slice::from_ref(&lib));
    // config.h may still be found in a system directory, never in ours.
    assert!(watched.contains(&lib.join("libfreenect2.a")), "{watched:?}");
    assert!(!watched
        .iter()
        .any(|p| p.starts_with(prefix.path().join("nowhere"))));
}

#[test]
fn pipelines_follow_the_defines_of_config_h() {
    let cpu_only = "#ifndef LIBFREENECT2_CONFIG_H\n#define LIBFREENECT2_CONFIG_H\n\
                    #define LIBFREENECT2_WITH_TURBOJPEG_SUPPORT\n/* #undef LIBFREENECT2_WITH_OPENCL_SUPPORT */\n";
    assert_eq!(pipelines_in_config_h(cpu_only), vec!["cpu"]);
    let gpu =
        "#define LIBFREENECT2_WITH_OPENCL_SUPPORT\n  #define   LIBFREENECT2_WITH_CUDA_SUPPORT\n\
               #define LIBFREENECT2_WITH_OPENGL_SUPPORT\n";
    assert_eq!(
        pipelines_in_config_h(gpu),
        vec!["cpu", "cl", "clkde", "cuda", "cudakde", "gl"]
    );
}

/// The shim reports exactly the pipelines of the `config.h` the build
/// script watched: had it been compiled against another libfreenect2, the
/// lists would differ.
#[cfg(feature = "kinect2")]
#[test]
fn the_shim_offers_the_pipelines_of_the_watched_config_h() {
    let Some(path) = option_env!("SLOPE_FREENECT2_CONFIG_H") else {
        panic!("build.rs found no libfreenect2/config.h to watch");
    };
    let text = std::fs::read_to_string(path).expect("config.h is readable");
    let mut expected = pipelines_in_config_h(&text);
    expected.insert(0, "default");
    let available: Vec<&str> = slope_sensor::kinect2::Pipeline::available()
        .into_iter()
        .map(|p| p.name())
        .collect();
    assert_eq!(available, expected, "{path}");
}

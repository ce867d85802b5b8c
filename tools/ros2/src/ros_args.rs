//! ROS 2's own command-line arguments (`--ros-args ...`), as a node
//! launched by ROS 2's tools gets them, turned into our flags
//! ([`translate`]).
//!
//! `ros2 run` and launch files pass parameters and remappings after
//! `--ros-args` (until `--` or the end): `-p frame_id:=camera_depth_optical_frame`,
//! `-r __ns:=/robot1`, `-r __node:=slope`. The node reads the parameters it
//! has, `frame_id` and `base_frame`, and the namespace and node name
//! remappings; everything else ROS 2 defines there (other parameters,
//! topic remappings, `--params-file`, `--log-level`, `--enclave`) is a
//! usage error that names it, not silently ignored.

use std::ffi::OsString;

/// The parameters `-p name:=value` sets, and the flag each becomes.
pub const PARAMETERS: [(&str, &str); 2] =
    [("frame_id", "--frame-id"), ("base_frame", "--base-frame")];

/// The remappings `-r from:=to` takes, and the flag each becomes.
const REMAPS: [(&str, &str); 3] = [
    ("__ns", "--namespace"),
    ("__node", "--node-name"),
    ("__name", "--node-name"),
];

/// `args` (the program's name first) with every `--ros-args` section
/// replaced by our flags; the arguments outside them kept as they are.
/// `Err` names what is not supported, or what is malformed.
pub fn translate(args: impl IntoIterator<Item = OsString>) -> Result<Vec<OsString>, String> {
    let mut out = Vec::new();
    let mut args = args.into_iter();
    while let Some(arg) = args.next() {
        if arg != "--ros-args" {
            out.push(arg);
            continue;
        }
        while let Some(arg) = args.next() {
            if arg == "--" {
                break;
            }
            let text = arg
                .to_str()
                .ok_or_else(|| format!("--ros-args: '{}' is not UTF-8", arg.to_string_lossy()))?;
            match text {
                "-p" | "--param" => {
                    let (name, value) = assignment(text, args.next())?;
                    out.push(flag_of(&PARAMETERS, &name, "parameter")?.into());
                    out.push(value.into());
                }
                "-r" | "--remap" => {
                    let (from, to) = assignment(text, args.next())?;
                    out.push(flag_of(&REMAPS, &from, "remapping")?.into());
                    out.push(to.into());
                }
                "--ros-args" => {}
                other => {
                    return Err(format!(
                        "--ros-args: '{other}' is not supported by slope-ros2 (it takes \
                         {}; and -r __ns:=, -r __node:=)",
                        supported_parameters()
                    ))
                }
            }
        }
    }
    Ok(out)
}

/// `name:=value` after `option`, its value unquoted (a YAML string
/// `"..."` or `'...'`, as launch files write them).
fn assignment(option: &str, next: Option<OsString>) -> Result<(String, String), String> {
    let text = next
        .as_ref()
        .and_then(|arg| arg.to_str())
        .ok_or_else(|| format!("--ros-args: {option} needs name:=value"))?;
    let (name, value) = text
        .split_once(":=")
        .ok_or_else(|| format!("--ros-args: {option} '{text}' is not name:=value"))?;
    let unquoted = ['"', '\'']
        .iter()
        .find_map(|q| value.strip_prefix(*q).and_then(|v| v.strip_suffix(*q)))
        .unwrap_or(value);
    Ok((name.trim().to_string(), unquoted.to_string()))
}

/// The flag `name` becomes, from `table`.
fn flag_of(
    table: &[(&'static str, &'static str)],
    name: &str,
    what: &str,
) -> Result<&'static str, String> {
    table
        .iter()
        .find(|(known, _)| *known == name)
        .map(|(_, flag)| *flag)
        .ok_or_else(|| {
            format!(
                "--ros-args: the {what} '{name}' is not supported by slope-ros2 (it takes {}; \
                 and -r __ns:=, -r __node:=)",
                supported_parameters()
            )
        })
}

/// "-p frame_id:=, -p base_frame:=".
fn supported_parameters() -> String {
    PARAMETERS
        .iter()
        .map(|(name, _)| format!("-p {name}:="))
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(args: &[&str]) -> Result<Vec<String>, String> {
        translate(args.iter().map(OsString::from)).map(|out| {
            out.into_iter()
                .map(|a| a.into_string().expect("utf-8"))
                .collect()
        })
    }

    #[test]
    fn parameters_and_remappings_become_our_flags_in_their_order() {
        assert_eq!(
            run(&[
                "slope-ros2",
                "-v",
                "--ros-args",
                "-p",
                "frame_id:=camera_depth_optical_frame",
                "-r",
                "__ns:=/robot1",
                "--remap",
                "__node:=slope",
                "--param",
                "base_frame:='base_link'",
                "--",
                "--domain-id",
                "3",
            ]),
            Ok(vec![
                "slope-ros2".to_string(),
                "-v".into(),
                "--frame-id".into(),
                "camera_depth_optical_frame".into(),
                "--namespace".into(),
                "/robot1".into(),
                "--node-name".into(),
                "slope".into(),
                "--base-frame".into(),
                "base_link".into(),
                "--domain-id".into(),
                "3".into(),
            ])
        );
        // Without --ros-args nothing changes.
        let plain = ["slope-ros2", "--frame-id", "cam", "-p"];
        assert_eq!(
            run(&plain),
            Ok(plain.iter().map(|a| a.to_string()).collect())
        );
        // A section may end the line, and come twice.
        assert_eq!(
            run(&[
                "slope-ros2",
                "--ros-args",
                "-r",
                "__name:=n",
                "--ros-args",
                "-p",
                "frame_id:=\"f\""
            ]),
            Ok(vec![
                "slope-ros2".to_string(),
                "--node-name".into(),
                "n".into(),
                "--frame-id".into(),
                "f".into()
            ])
        );
    }

    #[test]
    fn what_the_node_does_not_take_is_named() {
        let refused = |args: &[&str], expected: &str| {
            let err = run(args).expect_err("refused");
            assert!(err.contains(expected), "{err}");
        };
        refused(
            &["n", "--ros-args", "-p", "use_sim_time:=true"],
            "parameter 'use_sim_time'",
        );
        refused(
            &["n", "--ros-args", "-r", "/slope/estimate:=/x"],
            "remapping '/slope/estimate'",
        );
        refused(
            &["n", "--ros-args", "--params-file", "p.yaml"],
            "'--params-file' is not supported",
        );
        refused(&["n", "--ros-args", "-p"], "-p needs name:=value");
        refused(
            &["n", "--ros-args", "-p", "frame_id=x"],
            "is not name:=value",
        );
        let err = run(&["n", "--ros-args", "--log-level", "debug"]).expect_err("refused");
        assert!(err.contains("-p frame_id:=, -p base_frame:="), "{err}");
    }
}

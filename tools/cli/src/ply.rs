//! `--export-ply`: a frame's cloud as a binary PLY file that CloudCompare,
//! MeshLab and Open3D (`o3d.io.read_point_cloud`) read, written with the
//! `ply-rs-bw` crate.
//!
//! Element `vertex`, one per measured point: `x y z` (float, metres,
//! camera frame), `nx ny nz` (float: the paper method's normal where it
//! sampled one, else the point's plane's normal, else 0), `red green blue`
//! (uchar: the overlay's plane colours, depth grey elsewhere), `label`
//! (int: the index of the segmented plane holding the point, -1 for none)
//! and `role` (uchar: 0 none, 1 ground, 2 inclined, 3 another plane).

use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use anyhow::Context;
use ply_rs_bw::ply::{
    Addable, DefaultElement, ElementDef, Encoding, Ply, Property, PropertyDef, PropertyType,
    ScalarType,
};
use ply_rs_bw::writer::Writer;
use slope_ipc_types::CloudPoint;
use slope_pipeline::ransac_planes::SegmentedPlane;
use slope_pipeline::InspectedNormal;

use crate::overlay::{plane_colour, Role};

/// The `role` value of a point.
pub fn role_code(role: Option<Role>) -> u8 {
    match role {
        None => 0,
        Some(Role::Ground) => 1,
        Some(Role::Inclined) => 2,
        Some(Role::Other) => 3,
    }
}

/// A cloud with its planes, their roles and the sampled normals.
#[derive(Debug, Clone, Copy)]
pub struct LabelledCloud<'a> {
    pub points: &'a [CloudPoint],
    pub planes: &'a [SegmentedPlane],
    /// One per plane.
    pub roles: &'a [Role],
    pub normals: &'a [InspectedNormal],
}

const FLOATS: [&str; 6] = ["x", "y", "z", "nx", "ny", "nz"];
const COLOURS: [&str; 3] = ["red", "green", "blue"];

/// The PLY structure of a labelled cloud.
pub fn labelled_ply(cloud: &LabelledCloud<'_>) -> Ply<DefaultElement> {
    let n = cloud.points.len();
    let mut label = vec![-1i32; n];
    let mut normal = vec![[0.0f32; 3]; n];
    for (k, plane) in cloud.planes.iter().enumerate() {
        let pn = plane.plane.normal;
        for &i in &plane.inliers {
            if let Some(slot) = label.get_mut(i as usize) {
                *slot = k as i32;
                normal[i as usize] = [pn.x as f32, pn.y as f32, pn.z as f32];
            }
        }
    }
    for s in cloud.normals {
        if let Some(slot) = normal.get_mut(s.pixel as usize) {
            *slot = s.normal;
        }
    }
    let mut ply = Ply::<DefaultElement>::new();
    ply.header.encoding = Encoding::BinaryLittleEndian;
    ply.header
        .comments
        .push("slope: plane label and role per point (slope-eval --export-ply)".to_string());
    let mut vertex = ElementDef::new("vertex".to_string());
    let scalar =
        |name: &str, t: ScalarType| PropertyDef::new(name.to_string(), PropertyType::Scalar(t));
    for name in FLOATS {
        vertex.properties.add(scalar(name, ScalarType::Float));
    }
    for name in COLOURS {
        vertex.properties.add(scalar(name, ScalarType::UChar));
    }
    vertex.properties.add(scalar("label", ScalarType::Int));
    vertex.properties.add(scalar("role", ScalarType::UChar));
    ply.header.elements.add(vertex);

    let mut vertices = Vec::with_capacity(n);
    for (i, p) in cloud.points.iter().enumerate() {
        if !p.is_valid() {
            continue;
        }
        let k = label[i];
        let role = usize::try_from(k)
            .ok()
            .and_then(|k| cloud.roles.get(k).copied());
        let colour = match (usize::try_from(k), role) {
            (Ok(k), Some(role)) => plane_colour(k, role),
            _ => [128, 128, 128],
        };
        let [nx, ny, nz] = normal[i];
        let mut e = DefaultElement::new();
        for (name, value) in FLOATS.iter().zip([p.x_m, p.y_m, p.z_m, nx, ny, nz]) {
            e.insert((*name).to_string(), Property::Float(value));
        }
        for (name, value) in COLOURS.iter().zip(colour) {
            e.insert((*name).to_string(), Property::UChar(value));
        }
        e.insert("label".to_string(), Property::Int(k));
        e.insert("role".to_string(), Property::UChar(role_code(role)));
        vertices.push(e);
    }
    ply.payload.insert("vertex".to_string(), vertices);
    ply
}

/// Writes the labelled cloud to `path`.
pub fn write_labelled_cloud(path: &Path, cloud: &LabelledCloud<'_>) -> anyhow::Result<()> {
    let mut ply = labelled_ply(cloud);
    let file = File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    let mut out = BufWriter::new(file);
    Writer::new()
        .write_ply(&mut out, &mut ply)
        .with_context(|| format!("cannot write {}", path.display()))?;
    std::io::Write::flush(&mut out).with_context(|| format!("cannot write {}", path.display()))?;
    Ok(())
}

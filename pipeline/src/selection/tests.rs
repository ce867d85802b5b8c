//! Selection rules on analytic planes: each test fails without its rule.

use nalgebra::Vector3;

use super::*;
use crate::cloud::angle_between_deg;
use crate::fixtures::Scene;
use crate::sensor_noise::NoiseModel;

/// A flat plane summary for surface `k` of `scene`, seen in the camera
/// frame, with `pixels` inliers (a third of them in the bottom third of the
/// image for the ground, surface 0) and `area_m2` of surface; its centroid
/// half a metre into the surface along the world's forward axis.
fn summary(scene: &Scene, k: usize, pixels: usize, area_m2: f64) -> PlaneSummary {
    let s = &scene.surfaces[k];
    let n = scene.to_camera(&s.normal);
    let c = scene.to_camera(&(s.point - scene.camera_centre()));
    let ahead = scene.to_camera(&Vector3::new(0.0, 1.0, 0.0));
    let plane = Plane::from_point_normal(&c, &n)
        .unwrap()
        .oriented_towards(&Vector3::zeros());
    PlaneSummary {
        plane,
        inliers: pixels,
        bottom_pixels: if k == 0 { pixels / 3 } else { 0 },
        bottom_band_pixels: if k == 0 { pixels / 20 } else { 0 },
        lowest_row: if k == 0 { 1.0 } else { 0.0 },
        centroid: c + ahead * 0.5,
        quality: PlaneQuality {
            rms_m: 0.002,
            relative_rms: 0.1,
            area_m2,
            border_fraction: 0.0,
            noise_ratio: 1.2,
            veil_fraction: 0.0,
        },
    }
}

/// A level surface `height_m` above the ground (a bed, a table top) in
/// `scene`, as a summary: the ground plane raised.
fn raised(scene: &Scene, height_m: f64, pixels: usize, area_m2: f64) -> PlaneSummary {
    let mut s = summary(scene, 0, pixels, area_m2);
    s.bottom_pixels = 0;
    s.bottom_band_pixels = 0;
    s.lowest_row = 0.0;
    let up = s.plane.normal;
    s.plane.d -= height_m;
    s.centroid += up * height_m;
    s
}

fn mount_up(scene: &Scene) -> Option<Vector3<f64>> {
    scene.mount().up_vector().map(Vector3::from)
}

fn config() -> SelectionConfig {
    SelectionConfig::default()
}

#[test]
fn ramp_between_walls_is_measured_as_the_ramp() {
    for slope in [12.5, -12.5, 47.0] {
        let scene = Scene::ramp_between_walls(slope);
        // Walls get the most inliers: they must still not be chosen.
        let planes = vec![
            summary(&scene, 2, 9000, 2.0),
            summary(&scene, 0, 5000, 1.0),
            summary(&scene, 3, 8000, 2.0),
            summary(&scene, 1, 3000, 0.5),
        ];
        for up in [mount_up(&scene), None] {
            let sel = select_planes(&planes, up, None, &config()).unwrap();
            assert_eq!(sel.ground, Ground::Planes(vec![1]));
            assert_eq!(sel.inclined, 3);
            let angle = angle_between_deg(&planes[3].plane.normal, &sel.up);
            assert!((angle - slope.abs()).abs() < 1e-9);
            assert_eq!(
                slope_sign(&planes[3].plane.normal, &sel.forward),
                slope.signum()
            );
        }
    }
}

#[test]
fn no_ground_uses_the_mount_and_no_mount_is_an_error() {
    let scene = Scene::ramp(30.0);
    let planes = vec![summary(&scene, 1, 3000, 0.5)];
    let sel = select_planes(&planes, mount_up(&scene), None, &config()).unwrap();
    assert_eq!(sel.ground, Ground::Mount);
    assert!((angle_between_deg(&planes[0].plane.normal, &sel.up) - 30.0).abs() < 1e-9);
    let wall = Scene::wall_facing(2.0);
    let planes = vec![summary(&wall, 0, 3000, 1.0)];
    assert_eq!(
        select_planes(&planes, None, None, &config()),
        Err(EstimateStatus::NoGround)
    );
    let flat = Scene::ramp(0.0);
    let planes = vec![summary(&flat, 0, 3000, 1.0), summary(&flat, 1, 2000, 0.5)];
    assert_eq!(
        select_planes(&planes, mount_up(&flat), None, &config()),
        Err(EstimateStatus::NoInclinedPlane)
    );
}

/// A bed top 0.7 m above the floor, with ten times the floor's pixels, is
/// not the ground: the floor is lower. Its side is then no slope.
#[test]
fn the_lowest_supported_level_plane_is_the_ground() {
    let scene = Scene::ramp(16.0);
    let planes = vec![
        raised(&scene, 0.7, 40_000, 2.0),
        summary(&scene, 0, 4000, 0.3),
        summary(&scene, 1, 6000, 0.5),
    ];
    for up in [mount_up(&scene), None] {
        let sel = select_planes(&planes, up, None, &config()).unwrap();
        assert_eq!(sel.ground, Ground::Planes(vec![1]), "{up:?}");
        assert_eq!(sel.inclined, 2);
    }
    // Too small a floor patch (pixels or area) does not count.
    for (pixels, area) in [(1000, 0.3), (4000, 0.05)] {
        let mut small = planes.clone();
        small[1] = summary(&scene, 0, pixels, area);
        let sel = select_planes(&small, mount_up(&scene), None, &config()).unwrap();
        assert_eq!(sel.ground, Ground::Planes(vec![0]));
    }
}

/// The mount says where the ground is: a table top 0.75 m above it is not,
/// and with no level plane at the mount's height the mount's plane is the
/// ground and the ramp is still measured.
#[test]
fn with_a_known_height_the_ground_is_at_the_mount_height() {
    let scene = Scene::ramp(16.0);
    let height = scene.camera_height_m;
    let planes = vec![
        raised(&scene, 0.75, 40_000, 2.0),
        summary(&scene, 1, 6000, 0.5),
    ];
    let sel = select_planes(&planes, mount_up(&scene), Some(height), &config()).unwrap();
    assert_eq!(sel.ground, Ground::Mount);
    assert_eq!(sel.inclined, 1);
    assert!((angle_between_deg(&planes[1].plane.normal, &sel.up) - 16.0).abs() < 1e-9);
    // The floor within the tolerance is the ground.
    let mut with_floor = planes.clone();
    with_floor.push(raised(&scene, 0.1, 3000, 0.3));
    let sel = select_planes(&with_floor, mount_up(&scene), Some(height), &config()).unwrap();
    assert_eq!(sel.ground, Ground::Planes(vec![2]));
    // Without the height, the table is the only level plane, so the ground.
    let sel = select_planes(&planes, mount_up(&scene), None, &config()).unwrap();
    assert_eq!(sel.ground, Ground::Planes(vec![0]));
}

/// Two pieces of one floor (2 cm apart at the second's centroid) are one
/// ground; a tread 17 cm up is not part of it.
#[test]
fn the_ground_is_measured_on_all_of_its_segments() {
    let scene = Scene::ramp(90.0);
    let planes = vec![
        summary(&scene, 0, 30_000, 1.0),
        raised(&scene, 0.17, 20_000, 0.5),
        raised(&scene, 0.02, 8000, 0.4),
        summary(&scene, 1, 6000, 0.3),
    ];
    let sel = select_planes(&planes, mount_up(&scene), None, &config()).unwrap();
    assert_eq!(sel.ground, Ground::Planes(vec![0, 2]));
    assert_eq!(sel.inclined, 3);
}

/// A surface facing down (a ceiling, an overhang) is never the inclined
/// plane, however near; a wall is.
#[test]
fn surfaces_facing_down_are_never_inclined() {
    let scene = Scene::ramp(90.0);
    let mut ceiling = raised(&scene, 2.2, 20_000, 3.0);
    // Seen from below: normal towards the camera, i.e. down, tilted 20
    // degrees towards the robot so that it has a heading.
    let down = -ceiling.plane.normal;
    let back = scene.to_camera(&Vector3::new(0.0, -1.0, 0.0));
    let n = (down * 20f64.to_radians().cos() + back * 20f64.to_radians().sin()).normalize();
    ceiling.centroid = scene.to_camera(&(Vector3::new(0.0, 1.0, 2.2) - scene.camera_centre()));
    ceiling.plane = Plane::from_point_normal(&ceiling.centroid, &n)
        .unwrap()
        .oriented_towards(&Vector3::zeros());
    let planes = vec![
        summary(&scene, 0, 30_000, 1.0),
        ceiling,
        summary(&scene, 1, 6000, 0.3),
    ];
    let sel = select_planes(&planes, mount_up(&scene), None, &config()).unwrap();
    assert_eq!(sel.inclined, 2);
    assert!(angle_between_deg(&planes[1].plane.normal, &sel.up) > 150.0);
}

/// Ground, a nearer and larger copy of the ramp spoilt by `spoil`, and the
/// ramp itself (a smaller, farther plane).
fn ramp_behind_a_spoilt_copy(
    scene: &Scene,
    spoil: impl Fn(&mut PlaneSummary),
) -> Vec<PlaneSummary> {
    let mut spoilt = summary(scene, 1, 9000, 0.6);
    spoilt.centroid *= 0.5;
    spoil(&mut spoilt);
    vec![
        summary(scene, 0, 30_000, 1.0),
        spoilt,
        summary(scene, 1, 6000, 0.3),
    ]
}

/// A rough surface (relative RMS 0.55) is neither ground nor inclined plane,
/// even at 1.2 sensor deviations (a person's legs before a Kinect v1); a
/// floor that fills its band only as wide as the sensor's noise (a Kinect
/// v1 floor 3 m away) is the ground all the same.
#[test]
fn rough_surfaces_are_not_planes() {
    let scene = Scene::ramp(30.0);
    let planes = ramp_behind_a_spoilt_copy(&scene, |p| p.quality.relative_rms = 0.55);
    let sel = select_planes(&planes, mount_up(&scene), None, &config()).unwrap();
    assert_eq!(sel.inclined, 2);
    let mut rough_floor = planes.clone();
    rough_floor[0].quality.relative_rms = 0.55;
    rough_floor[0].quality.noise_ratio = 2.0;
    rough_floor.truncate(1);
    assert_eq!(
        select_planes(&rough_floor, None, None, &config()),
        Err(EstimateStatus::NoGround)
    );
    rough_floor[0].quality.noise_ratio = GROUND_NOISE_RATIO;
    assert_eq!(
        select_planes(&rough_floor, None, None, &config()),
        Err(EstimateStatus::NoInclinedPlane)
    );
}

/// A plane made mostly of veil points (mixed readings along a depth edge)
/// is no surface: neither ground nor inclined plane.
#[test]
fn veil_planes_are_not_surfaces() {
    let scene = Scene::ramp(30.0);
    let planes = ramp_behind_a_spoilt_copy(&scene, |p| p.quality.veil_fraction = 0.6);
    let sel = select_planes(&planes, mount_up(&scene), None, &config()).unwrap();
    assert_eq!(sel.inclined, 2);
    let mut veil_floor = planes.clone();
    veil_floor[0].quality.veil_fraction = 0.6;
    veil_floor.truncate(1);
    assert_eq!(
        select_planes(&veil_floor, None, None, &config()),
        Err(EstimateStatus::NoGround)
    );
}

/// A surface flat within the RANSAC band but 3.8 sensor deviations rough
/// (a piece of a bed's fabric side) is not the inclined plane; the ground,
/// judged by the band only, may be that rough (a gently bent floor).
#[test]
fn the_inclined_plane_is_flat_at_the_sensors_noise_level() {
    let scene = Scene::ramp(30.0);
    let planes = ramp_behind_a_spoilt_copy(&scene, |p| p.quality.noise_ratio = 3.8);
    let sel = select_planes(&planes, mount_up(&scene), None, &config()).unwrap();
    assert_eq!(sel.inclined, 2);
    assert_eq!(
        select_planes(&planes[..2], mount_up(&scene), None, &config()),
        Err(EstimateStatus::NoInclinedPlane)
    );
    let mut bent_floor = planes.clone();
    bent_floor[0].quality.noise_ratio = 3.3;
    let sel = select_planes(&bent_floor, mount_up(&scene), None, &config()).unwrap();
    assert_eq!((sel.ground, sel.inclined), (Ground::Planes(vec![0]), 2));
}

/// A flat patch of less than `inclined_min_area_m2` (0.04 m^2) is not the
/// inclined plane, however near: the farther ramp is; with 0.05 m^2 the
/// nearer patch is.
#[test]
fn the_inclined_plane_has_the_minimum_area() {
    let scene = Scene::ramp(30.0);
    assert_eq!(config().inclined_min_area_m2, 0.04);
    for (area_m2, expected) in [(0.03, 2), (0.05, 1)] {
        let planes = ramp_behind_a_spoilt_copy(&scene, |p| p.quality.area_m2 = area_m2);
        let sel = select_planes(&planes, mount_up(&scene), None, &config()).unwrap();
        assert_eq!(sel.inclined, expected, "{area_m2}");
    }
    let planes = ramp_behind_a_spoilt_copy(&scene, |p| p.quality.area_m2 = 0.03);
    assert_eq!(
        select_planes(&planes[..2], mount_up(&scene), None, &config()),
        Err(EstimateStatus::NoInclinedPlane)
    );
}

/// A copy of the ramp whose centroid lies behind the camera (its distance
/// along forward negative, so the "nearest") is not the inclined plane.
#[test]
fn the_inclined_plane_lies_ahead() {
    let scene = Scene::ramp(30.0);
    for up in [mount_up(&scene), None] {
        let planes = ramp_behind_a_spoilt_copy(&scene, |p| p.centroid = -p.centroid);
        let sel = select_planes(&planes, up, None, &config()).unwrap();
        assert!(planes[1].centroid.dot(&sel.forward) < 0.0);
        assert_eq!(sel.inclined, 2, "{up:?}");
        assert_eq!(
            select_planes(&planes[..2], up, None, &config()),
            Err(EstimateStatus::NoInclinedPlane)
        );
    }
}

/// The nearest candidate is passed over when it has fewer than
/// `min_relative_support` (a quarter) of the best-supported candidate's
/// pixels: 1000 of 6000 is passed over, 2000 of 6000 is not.
#[test]
fn the_nearest_inclined_plane_has_a_quarter_of_the_best_support() {
    let scene = Scene::ramp(30.0);
    assert_eq!(config().min_relative_support, 0.25);
    for (pixels, expected) in [(1000, 2), (2000, 1)] {
        let planes = ramp_behind_a_spoilt_copy(&scene, |p| p.inliers = pixels);
        let sel = select_planes(&planes, mount_up(&scene), None, &config()).unwrap();
        assert_eq!(sel.inclined, expected, "{pixels}");
    }
}

/// The sensor's floor bend at a plane's depth makes "level" and "inclined":
/// a plane 0.1 degrees inside the Kinect v2's bend at its centroid is no
/// slope, 0.1 degrees beyond it is (a 3.9 degree ramp is a slope).
#[test]
fn the_floor_bend_at_its_depth_makes_a_plane_inclined() {
    let depth = summary(&Scene::ramp(3.0), 1, 6000, 0.5).centroid.z;
    let bend = NoiseModel::Kinect2.floor_bend_deg(depth);
    assert!(bend > 1.0 && bend < 3.0, "{bend} at {depth} m");
    for (slope, expected) in [
        (bend - 0.1, Err(EstimateStatus::NoInclinedPlane)),
        (bend + 0.1, Ok(1)),
        (3.9, Ok(1)),
    ] {
        let scene = Scene::ramp(slope);
        let planes = vec![
            summary(&scene, 0, 30_000, 1.0),
            summary(&scene, 1, 6000, 0.5),
        ];
        // The ramp's centroid moves little with its slope.
        assert!((planes[1].centroid.z - depth).abs() < 0.05);
        let sel = select_planes(&planes, mount_up(&scene), None, &config());
        assert_eq!(sel.map(|s| s.inclined), expected, "{slope}");
    }
}

/// A ground of no plane, or of an index that is not one of `planes`, has
/// no inclined plane over it (the error gives the ground back), however
/// good a ramp is in the list.
#[test]
fn a_ground_without_a_plane_of_the_list_has_no_inclined_plane() {
    let scene = Scene::ramp(16.0);
    let planes = vec![
        summary(&scene, 0, 30_000, 1.0),
        summary(&scene, 1, 6000, 0.5),
    ];
    let sel = select_inclined(&planes, Ground::Planes(vec![0]), None, &config()).unwrap();
    assert_eq!(sel.inclined, 1);
    for ground in [Ground::Planes(vec![]), Ground::Planes(vec![2, 0])] {
        assert_eq!(
            select_inclined(&planes, ground.clone(), mount_up(&scene), &config()),
            Err(ground)
        );
    }
    assert_eq!(
        select_inclined(&[], Ground::Planes(vec![0]), None, &config()),
        Err(Ground::Planes(vec![0]))
    );
}

#[test]
fn distance_along_the_axis() {
    let plane =
        Plane::from_point_normal(&Vector3::new(0.0, 0.0, 3.0), &Vector3::new(0.0, -1.0, -1.0))
            .unwrap();
    assert!((axis_distance(&plane) - 3.0).abs() < 1e-12);
    let parallel = Plane::from_point_normal(&Vector3::new(0.0, 1.0, 0.0), &Vector3::y()).unwrap();
    assert!(axis_distance(&parallel).is_nan());
}

/// The floor seen against the mount: agreeing, tilted 20 degrees from it
/// (the ground then comes from the mount), or 0.3 m off its height.
#[test]
fn a_floor_that_disagrees_with_the_mount_is_reported() {
    let scene = Scene::ramp(16.0);
    let planes = vec![
        summary(&scene, 0, 30_000, 1.0),
        summary(&scene, 1, 6000, 0.5),
    ];
    let up = mount_up(&scene).unwrap();
    let height = planes[0].plane.d;
    let check = |up: Vector3<f64>, height: f64| {
        let ground = select_ground(&planes, Some(up), Some(height), &config()).unwrap();
        (
            ground.clone(),
            mount_disagrees(&planes, &ground, Some(up), Some(height), &config()),
        )
    };
    assert_eq!(check(up, height), (Ground::Planes(vec![0]), false));
    let tilted = nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), 20f64.to_radians()) * up;
    assert_eq!(check(tilted, height), (Ground::Mount, true));
    assert!(check(up, height + 0.3).1);
    // Without a mount there is nothing to disagree with.
    assert!(!mount_disagrees(
        &planes,
        &Ground::Planes(vec![0]),
        None,
        None,
        &config()
    ));
}

//! Where a housing's sun shadow falls ([`poser::geometry::shadow`]), the numbers behind
//! Mitsuba's housing-shadow warning: on tests/canonical/sun_seabed.toml (a nadir camera 2 m
//! over a flat seabed, flat port, sun at 60°) the shadow is in the image, where a Mitsuba
//! render shows it (docs/backends.md, "The housing's shadow"); with a low sun it leaves the
//! frame; a target on the shadow is named, the same target a metre aside is not.

use crate::support::column::load_text;
use glam::DVec3;
use poser::geometry::Bvh;
use poser::geometry::shadow::{HousingShadow, housing_shadow};
use poser::model::Model;

const SCENE: &str = include_str!("canonical/sun_seabed.toml");

fn shadow(m: &Model) -> HousingShadow {
    let scene = Bvh::of_model(m).unwrap();
    housing_shadow(m, &scene).expect("a sun and a port housing")
}

/// Where the shadow's axis from the camera's pupil meets the seabed (z = −5 m).
fn shadow_centre(m: &Model) -> DVec3 {
    let pupil = m.world_from_camera(0, 0).translation;
    let d = m.sun.as_ref().unwrap().direction_water;
    pupil + d * ((-5.0 - pupil.z) / d.z)
}

/// The scene with two 10 mm disks 20 mm apart along +x, the first at `p` (on the seabed).
fn with_grid_at(p: DVec3) -> String {
    format!(
        "{SCENE}\n[[targets]]\nname = \"grid\"\ntype = \"circle_grid\"\ncols = 2\nrows = 1\n\
         spacing = \"20 mm\"\ndiameter = \"10 mm\"\nposition = [{}, {}, -4.99]\n",
        p.x, p.y
    )
}

#[test]
fn the_shadow_of_a_nadir_camera_under_a_high_sun_is_in_its_image() {
    let m = load_text(SCENE, &[]);
    let s = shadow(&m);
    assert_eq!((s.images, s.of), (1, 1), "{s:?}");
    assert!(s.points.is_empty(), "no targets: {s:?}");
    assert!(
        s.describe().starts_with("it falls inside 1 of 1 images"),
        "{}",
        s.describe()
    );
    // The shadow's centre is in view, off the image's centre.
    let c = shadow_centre(&m);
    let px = m.projector(0, 1).unwrap().project_world(0, c).unwrap();
    assert!(
        px[0] > 0.0 && px[0] < 160.0 && px[1] > 0.0 && px[1] < 120.0,
        "{px:?}"
    );
}

#[test]
fn a_low_sun_throws_the_shadow_out_of_the_frame() {
    let m = load_text(SCENE, &["sun.elevation=\"10 deg\"".into()]);
    let s = shadow(&m);
    assert_eq!((s.images, s.of), (0, 1), "{s:?}");
    assert_eq!(s.describe(), "it falls outside every image (1 checked)");
}

#[test]
fn a_target_in_the_shadow_is_named_and_one_beside_it_is_not() {
    let base = load_text(SCENE, &[]);
    let c = shadow_centre(&base);
    // The shadow's centre is at the image's corner: the disks 3 cm in from it.
    let on = shadow(&load_text(
        &with_grid_at(c + DVec3::new(0.03, -0.03, 0.0)),
        &[],
    ));
    let ids: Vec<&str> = on.points.iter().map(|(_, id)| id.as_str()).collect();
    assert_eq!(ids.len(), 2, "both disks lie in the shadow: {on:?}");
    assert!(
        on.describe().contains("on 2 target point(s)"),
        "{}",
        on.describe()
    );
    // 0.4 m towards the image's centre: still in view, out of the 0.1 m shadow.
    let aside = c + (DVec3::new(0.0, 0.0, c.z) - c).normalize_or_zero() * 0.4;
    let m = load_text(&with_grid_at(aside), &[]);
    let px = m.projector(0, 1).unwrap().project_world(0, aside).unwrap();
    assert!(m.projector(0, 1).unwrap().on_sensor(px), "{px:?}");
    let off = shadow(&m);
    assert!(off.points.is_empty(), "{off:?}");
    assert_eq!(off.images, 1);
}

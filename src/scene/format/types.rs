//! The scene format as Rust types: every table a struct, every key a field, spelled once. The
//! JSON Schema and `docs/format.md` are generated from these types ([`super::docgen`]), and
//! `#[derive(Keys)]` turns each field into the constant through which the reader's resolvers
//! and the importers name the key (`Light::beam_angle == "beam_angle"`, `Light::kind ==
//! "type"`). The types document; the reading itself is done by [`crate::scene::resolve`] with
//! full diagnostics, and a test checks both agree key by key.
//!
//! Values with a physical dimension accept a plain number in the SI unit or a string with a
//! unit (`"18 mm"`); see [`crate::units`]. Every field's doc comment gives its unit and
//! default.
#![allow(dead_code)]

use poser_keys::Keys;
use schemars::{JsonSchema, Schema, SchemaGenerator, json_schema};
use std::borrow::Cow;
use std::marker::PhantomData;

/// A physical dimension, for the schema of quantity values.
pub trait Quantity {
    const NAME: &'static str;
    /// SI unit of plain numbers.
    const UNIT: &'static str;
    /// Example string.
    const EXAMPLE: &'static str;
}

macro_rules! quantity {
    ($t:ident, $name:expr, $unit:expr, $ex:expr) => {
        #[doc = concat!("A ", $name, ": a number in ", $unit, " or a string like `\"", $ex, "\"`.")]
        pub struct $t;
        impl Quantity for $t {
            const NAME: &'static str = $name;
            const UNIT: &'static str = $unit;
            const EXAMPLE: &'static str = $ex;
        }
        impl JsonSchema for $t {
            fn inline_schema() -> bool {
                true
            }
            fn schema_name() -> Cow<'static, str> {
                Cow::Borrowed(stringify!($t))
            }
            fn json_schema(_: &mut SchemaGenerator) -> Schema {
                scalar_schema::<$t>()
            }
        }
    };
}

fn scalar_schema<Q: Quantity>() -> Schema {
    if Q::UNIT.is_empty() {
        return json_schema!({ "type": "number", "x-poser-kind": Q::NAME });
    }
    json_schema!({
        "anyOf": [
            { "type": "number" },
            { "type": "string", "pattern": "^\\s*[-+]?[0-9_.]+([eE][-+]?[0-9]+)?\\s*\\S*" }
        ],
        "x-poser-kind": Q::NAME,
        "x-poser-unit": Q::UNIT,
        "x-poser-example": Q::EXAMPLE
    })
}

quantity!(Length, "length", "m", "18 mm");
quantity!(Angle, "angle", "rad", "30 deg");
quantity!(Degrees, "angle", "deg", "43.5");
quantity!(Speed, "speed", "m/s", "0.2 m/s");
quantity!(Flow, "gas flow", "m³/s", "20 l/min");
quantity!(Pressure, "pressure", "Pa", "232 bar");
quantity!(Volume, "volume", "m³", "12 l");
quantity!(Power, "power", "W", "50 W");
quantity!(Intensity, "radiant intensity", "W/sr", "4 W/sr");
quantity!(Radiance, "radiance", "W/(m²·sr)", "1 W/m2/sr");
quantity!(Irradiance, "irradiance", "W/m²", "800 W/m2");
quantity!(Temperature, "temperature", "°C", "18 °C");
quantity!(Fraction, "fraction", "1", "60 %");
quantity!(Gsd, "ground sampling distance", "m/px", "1 mm/px");
quantity!(Number, "number", "", "1");
quantity!(Duration, "time", "s", "8 ms");

/// A 3-vector of a quantity: `[x, y, z]` (numbers or unit strings) or one string
/// `"x, y, z unit"`.
pub struct Vec3<Q>(PhantomData<Q>);
impl<Q: Quantity> JsonSchema for Vec3<Q> {
    fn inline_schema() -> bool {
        true
    }
    fn schema_name() -> Cow<'static, str> {
        Cow::Owned(format!("Vec3_{}", Q::NAME))
    }
    fn json_schema(_: &mut SchemaGenerator) -> Schema {
        json_schema!({
            "anyOf": [
                { "type": "array", "items": scalar_schema::<Q>(), "minItems": 3, "maxItems": 3 },
                { "type": "string" }
            ],
            "x-poser-kind": format!("3-vector of {}", Q::NAME),
            "x-poser-unit": Q::UNIT
        })
    }
}

/// A list of a quantity: `[a, b, …]` or one string `"a, b, … unit"`.
pub struct List<Q>(PhantomData<Q>);
impl<Q: Quantity> JsonSchema for List<Q> {
    fn inline_schema() -> bool {
        true
    }
    fn schema_name() -> Cow<'static, str> {
        Cow::Owned(format!("List_{}", Q::NAME))
    }
    fn json_schema(_: &mut SchemaGenerator) -> Schema {
        json_schema!({
            "anyOf": [ { "type": "array", "items": scalar_schema::<Q>() }, { "type": "string" } ],
            "x-poser-kind": format!("list of {}", Q::NAME),
            "x-poser-unit": Q::UNIT
        })
    }
}

/// A per-channel value: one value for R, G and B, or `[r, g, b]`.
pub struct PerChannel<Q>(PhantomData<Q>);
impl<Q: Quantity> JsonSchema for PerChannel<Q> {
    fn inline_schema() -> bool {
        true
    }
    fn schema_name() -> Cow<'static, str> {
        Cow::Owned(format!("PerChannel_{}", Q::NAME))
    }
    fn json_schema(_: &mut SchemaGenerator) -> Schema {
        json_schema!({
            "anyOf": [
                scalar_schema::<Q>(),
                { "type": "array", "items": scalar_schema::<Q>(), "minItems": 3, "maxItems": 3 }
            ],
            "x-poser-kind": format!("{} per channel (one value or [r, g, b])", Q::NAME),
            "x-poser-unit": Q::UNIT
        })
    }
}

// ------------------------------------------------------------------------------------------

/// A poser scene: one survey — water, site, sun, camera rig with housing ports, lights,
/// objects, targets, camera network, diver and render settings. Every table is optional
/// except `[network]`; without `[water]` the survey is in air.
#[derive(JsonSchema, Keys)]
#[schemars(title = "poser scene", deny_unknown_fields)]
pub struct Scene {
    /// Scenario name. **Default:** the file name without `.toml`.
    pub name: Option<String>,
    /// Free text for trainers. **Default:** empty.
    pub description: Option<String>,
    /// Files merged *under* this one (paths relative to this file; tables deep-merge, later
    /// files and this file win; cycles are errors). **Default:** none.
    pub include: Option<Vec<String>>,
    pub site: Option<Site>,
    pub water: Option<Water>,
    pub sun: Option<Sun>,
    pub camera: Option<Camera>,
    pub rig: Option<Rig>,
    /// Lights other than the sun: `[[lights]]`, one table each.
    pub lights: Option<Vec<Light>>,
    /// Scene geometry: `[[objects]]`, one table each.
    pub objects: Option<Vec<Object>>,
    /// Calibration targets, scale bars, GSD targets: `[[targets]]`, one table each.
    pub targets: Option<Vec<Target>>,
    pub network: Option<Network>,
    pub diver: Option<Diver>,
    pub render: Option<Render>,
    pub sensor: Option<Sensor>,
    pub lesson: Option<LessonTable>,
}

/// `[site]` — where the survey happens. The sea surface is the plane z = 0 (z up).
#[derive(JsonSchema, Keys)]
#[schemars(deny_unknown_fields)]
pub struct Site {
    /// Depth of the nominal seabed below the surface. **Unit:** m. **Default:** 10 m.
    pub depth: Option<Length>,
    /// Sea surface model. **Default:** `"flat"` with water, `"none"` without.
    pub surface: Option<SurfaceKind>,
    /// Significant wave height (`surface = "waves"`). **Unit:** m. **Default:** 0.5 m.
    pub wave_height: Option<Length>,
    /// Dominant wavelength of the waves. **Unit:** m. **Default:** 10 m.
    pub wave_length: Option<Length>,
    /// Wind speed driving the waves. **Unit:** m/s. **Default:** 5 m/s.
    pub wind_speed: Option<Speed>,
    /// Altitude of the water surface above sea level (dive planning). **Unit:** m.
    /// **Default:** 0.
    pub altitude: Option<Length>,
    /// Seed of what the site generates: the waves, and the relief of every seabed, boulders
    /// and coral object without a `seed` of its own (this seed + the object's index). Apart
    /// from `render.seed`, so that a new render seed gives new noise on the same site.
    /// **Default:** 0.
    pub seed: Option<u64>,
}

/// Sea surface model.
#[derive(JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum SurfaceKind {
    /// No interface is modelled (sunlight is a directional light in the water).
    None,
    /// A flat air–water interface at z = 0.
    Flat,
    /// A wavy surface (`wave_height`, `wave_length`, `wind_speed`); gives caustics.
    Waves,
}

/// `[water]` — the medium. Without this table the survey is in air (no medium anywhere).
#[derive(JsonSchema, Keys)]
#[schemars(deny_unknown_fields)]
pub struct Water {
    /// Constant refractive index (one value or `[r, g, b]`). **Unit:** 1. **Default:**
    /// computed from `temperature`, `salinity`, `ior_depth` at 650/550/450 nm (Quan–Fry with
    /// Millard–Seaver pressure term).
    pub ior: Option<PerChannel<Number>>,
    /// Water temperature for the index. **Unit:** °C. **Default:** 20 °C.
    pub temperature: Option<Temperature>,
    /// Salinity for the index (0 fresh, 35 ocean). **Unit:** PSU. **Default:** 35.
    pub salinity: Option<Number>,
    /// Depth at which the index is evaluated (pressure term). **Unit:** m. **Default:** the
    /// site depth.
    pub ior_depth: Option<Length>,
    /// Jerlov water type giving absorption and scattering per channel: I, IA, IB, II, III,
    /// 1C, 3C, 5C, 7C, 9C. **Default:** `"IB"` unless `absorption`/`scattering` are given.
    pub jerlov: Option<String>,
    /// Absorption coefficient σa (overrides the Jerlov value). **Unit:** 1/m. **Default:**
    /// from `jerlov`, else 0.
    pub absorption: Option<PerChannel<Number>>,
    /// Scattering coefficient σs (overrides the Jerlov value). **Unit:** 1/m. **Default:**
    /// from `jerlov`, else 0.
    pub scattering: Option<PerChannel<Number>>,
    /// Phase function. **Default:** `"hg"`.
    pub phase: Option<PhaseKind>,
    /// Henyey–Greenstein asymmetry, in (-1, 1). **Unit:** 1. **Default:** 0.9.
    pub g: Option<Number>,
    /// Fournier–Forand: index of particles relative to water (> 1). **Unit:** 1.
    /// **Default:** 1.1.
    pub particle_index: Option<Number>,
    /// Fournier–Forand: Junge slope μ in (3, 5]. **Unit:** 1. **Default:** 3.6.
    pub junge_slope: Option<Number>,
    /// Where the medium is. **Default:** `"everywhere"`.
    pub extent: Option<ExtentKind>,
    /// Half-size of the medium box around each camera (`extent = "box"`), one value or
    /// `[x, y, z]`. **Unit:** m. **Default:** 2 m.
    pub box_half_size: Option<PerChannel<Length>>,
}

/// `fill = { … }` — the water inside a filled object: `[water]`'s keys but `extent` and
/// `box_half_size` (the object is its extent); each means what it means there.
#[derive(JsonSchema, Keys)]
#[schemars(deny_unknown_fields)]
pub struct FillTable {
    /// As `[water]`'s `ior`. **Unit:** 1. **Default:** from `temperature` and `salinity`.
    pub ior: Option<PerChannel<Number>>,
    /// As `[water]`'s. **Unit:** °C. **Default:** 20 °C.
    pub temperature: Option<Temperature>,
    /// As `[water]`'s. **Unit:** PSU. **Default:** 35.
    pub salinity: Option<Number>,
    /// As `[water]`'s. **Unit:** m. **Default:** the site depth.
    pub ior_depth: Option<Length>,
    /// As `[water]`'s. **Default:** `"IB"` unless `absorption`/`scattering` are given.
    pub jerlov: Option<String>,
    /// As `[water]`'s. **Unit:** 1/m. **Default:** from `jerlov`, else 0.
    pub absorption: Option<PerChannel<Number>>,
    /// As `[water]`'s. **Unit:** 1/m. **Default:** from `jerlov`, else 0.
    pub scattering: Option<PerChannel<Number>>,
    /// As `[water]`'s. **Default:** `"hg"`.
    pub phase: Option<PhaseKind>,
    /// As `[water]`'s. **Unit:** 1. **Default:** 0.9.
    pub g: Option<Number>,
    /// As `[water]`'s. **Unit:** 1. **Default:** 1.1.
    pub particle_index: Option<Number>,
    /// As `[water]`'s. **Unit:** 1. **Default:** 3.6.
    pub junge_slope: Option<Number>,
}

#[derive(JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum PhaseKind {
    /// Henyey–Greenstein with asymmetry `g`.
    Hg,
    /// Fournier–Forand with `particle_index` and `junge_slope` (where a backend supports it).
    FournierForand,
}

#[derive(JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ExtentKind {
    /// Water fills all space below the surface.
    Everywhere,
    /// Only a box around each camera (the original POSER's trick for fast volumes).
    Box,
}

/// `[sun]` — daylight. Give `elevation` (+ `azimuth`), or `latitude`, `longitude` and
/// `datetime`. Without this table there is no sun.
#[derive(JsonSchema, Keys)]
#[schemars(deny_unknown_fields)]
pub struct Sun {
    /// Elevation above the horizon. **Unit:** rad (or `"55 deg"`). **Default:** none.
    pub elevation: Option<Angle>,
    /// Azimuth, clockwise from north. **Unit:** rad (or `"140 deg"`). **Default:** 180°
    /// (south).
    pub azimuth: Option<Angle>,
    /// Latitude, north positive. **Unit:** degrees (plain numbers are degrees here).
    pub latitude: Option<Degrees>,
    /// Longitude, east positive. **Unit:** degrees (plain numbers are degrees here).
    pub longitude: Option<Degrees>,
    /// Local date and time with offset, e.g. `2024-06-21T10:30:00+02:00` (TOML date-time or
    /// string).
    pub datetime: Option<String>,
    /// Irradiance on a plane normal to the sun, above the surface. **Unit:** W/m² per
    /// channel. **Default:** 1.
    pub irradiance: Option<PerChannel<Irradiance>>,
}

/// `[camera]` — the camera (for a stereo or multi-camera rig: the template every camera of
/// the rig starts from).
#[derive(JsonSchema, Keys)]
#[schemars(deny_unknown_fields)]
pub struct Camera {
    /// Camera name (multi rigs). **Default:** `"cam"`, `"left"`/`"right"` (stereo),
    /// `"cam<i>"` (multi).
    pub name: Option<String>,
    /// Entrance-pupil position in the rig frame (multi rigs). **Unit:** m. **Default:** 0.
    pub position: Option<Vec3<Length>>,
    /// Orientation in the rig frame as rotations about x, y, z (applied x first; multi
    /// rigs). **Unit:** rad (or `"0, 30, 0 deg"`). **Default:** 0.
    pub rotation: Option<Vec3<Angle>>,
    /// Image width. **Unit:** px. **Default:** 1600.
    pub width: Option<u32>,
    /// Image height. **Unit:** px. **Default:** 1200.
    pub height: Option<u32>,
    /// Pixel pitch. **Unit:** m. **Default:** 3.76 µm (or from `sensor_width`).
    pub pixel_pitch: Option<Length>,
    /// Sensor width; the pixel pitch is `sensor_width / width`. **Unit:** m.
    pub sensor_width: Option<Length>,
    /// Focal length. **Unit:** m. **Default:** 16 mm.
    pub focal_length: Option<Length>,
    /// Focal length in pixels (instead of `focal_length`). **Unit:** px.
    pub fx: Option<Number>,
    /// Principal point `[cx, cy]`. **Unit:** px. **Default:** the image centre.
    pub principal_point: Option<List<Number>>,
    /// Lens projection. **Default:** `"rectilinear"`.
    pub lens: Option<LensKind>,
    /// Brown–Conrady distortion (OpenCV convention). **Default:** none.
    pub distortion: Option<DistortionTable>,
    /// Focus distance (depth of field). **Unit:** m. **Default:** pinhole (all sharp).
    pub focus_distance: Option<Length>,
    /// Aperture f-number. **Unit:** 1. **Default:** pinhole.
    pub f_number: Option<Number>,
    pub port: Option<PortTable>,
}

#[derive(JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum LensKind {
    /// r = f·tan θ.
    Rectilinear,
    /// r = f·θ.
    FisheyeEquidistant,
    /// r = 2f·sin(θ/2).
    FisheyeEquisolid,
}

/// `[camera.distortion]` — Brown–Conrady coefficients on normalised coordinates (OpenCV).
/// All default to 0.
#[derive(JsonSchema, Keys)]
#[schemars(deny_unknown_fields)]
pub struct DistortionTable {
    /// Radial k1. **Default:** 0.
    pub k1: Option<Number>,
    /// Radial k2. **Default:** 0.
    pub k2: Option<Number>,
    /// Radial k3. **Default:** 0.
    pub k3: Option<Number>,
    /// Tangential p1. **Default:** 0.
    pub p1: Option<Number>,
    /// Tangential p2. **Default:** 0.
    pub p2: Option<Number>,
}

/// `[camera.port]` — the housing port, in the camera frame (x right, y down, z forward,
/// origin at the entrance pupil). Which keys apply depends on `type`.
#[derive(JsonSchema, Keys)]
#[schemars(deny_unknown_fields)]
pub struct PortTable {
    /// Port kind. **Default:** `"flat"` with water, `"none"` in air.
    #[serde(rename = "type")]
    pub kind: Option<PortKind>,
    /// Catalogue material: `N-BK7`, `fused_silica`, `PMMA` (acrylic), `sapphire`.
    /// **Default:** `N-BK7` (flat), `PMMA` (dome, cylinder).
    pub material: Option<String>,
    /// Custom glass index instead of `material` (one value or `[r, g, b]`). **Unit:** 1.
    pub ior: Option<PerChannel<Number>>,
    /// Glass thickness (all kinds). **Unit:** m. **Default:** 10 mm (flat), 5 mm (dome,
    /// cylinder).
    pub thickness: Option<Length>,
    /// Flat: distance from the entrance pupil to the inner face of the glass. **Unit:** m.
    /// **Default:** 10 mm.
    pub pupil_distance: Option<Length>,
    /// Flat: tilt of the port normal away from the optical axis. **Unit:** rad.
    /// **Default:** 0.
    pub tilt: Option<Angle>,
    /// Flat: direction of the tilt axis in the image plane, from +x towards +y. **Unit:**
    /// rad. **Default:** 0 (tilt about the image x axis).
    pub tilt_direction: Option<Angle>,
    /// Dome, cylinder: inner radius. **Unit:** m. **Default:** 50 mm.
    pub inner_radius: Option<Length>,
    /// Dome: position of the dome centre relative to the entrance pupil (0 = perfectly
    /// centred). **Unit:** m. **Default:** `[0, 0, 0]`.
    pub decentering: Option<Vec3<Length>>,
    /// Cylinder: axis direction in the camera frame. **Unit:** 1. **Default:** `[0, 1, 0]`.
    pub axis: Option<Vec3<Number>>,
    /// Cylinder: a point of the axis relative to the entrance pupil. **Unit:** m.
    /// **Default:** `[0, 0, 0]`.
    pub offset: Option<Vec3<Length>>,
    /// Flat: two to four parallel glass layers, from the camera outwards, each with its
    /// `thickness` and `material` or `ior` (a laminated or coated window, a protective
    /// cover). Replaces the port's own `thickness`, `material` and `ior`. Only the native
    /// renderer and the ground truth model more than one layer; Mitsuba and Blender refuse.
    /// **Default:** one layer, from `thickness` and `material`.
    pub layers: Option<Vec<PortLayer>>,
}

/// `[[camera.port.layers]]` — one glass layer of a multi-layer flat port.
#[derive(JsonSchema, Keys)]
#[schemars(deny_unknown_fields)]
pub struct PortLayer {
    /// Layer thickness. **Unit:** m. Required.
    pub thickness: Length,
    /// Catalogue material, as the port's `material`. **Default:** `N-BK7`.
    pub material: Option<String>,
    /// Custom index instead of `material` (one value or `[r, g, b]`). **Unit:** 1.
    pub ior: Option<PerChannel<Number>>,
}

#[derive(JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum PortKind {
    /// No housing (air survey or an idealised camera).
    None,
    /// Flat port: `thickness`, `pupil_distance`, `tilt`, `tilt_direction`, `layers`.
    Flat,
    /// Dome port: `inner_radius`, `thickness`, `decentering`.
    Dome,
    /// Cylindrical port: `inner_radius`, `thickness`, `axis`, `offset`.
    Cylinder,
}

/// `[rig]` — how many cameras and where. Without it: one camera at the rig origin.
#[derive(JsonSchema, Keys)]
#[schemars(deny_unknown_fields)]
pub struct Rig {
    /// Rig kind. **Default:** `"single"`.
    #[serde(rename = "type")]
    pub kind: Option<RigKind>,
    /// Stereo: distance between the two entrance pupils (left at −x/2, right at +x/2).
    /// **Unit:** m. **Default:** 0.3 m.
    pub baseline: Option<Length>,
    /// Stereo: total toe-in angle between the two optical axes. **Unit:** rad.
    /// **Default:** 0.
    pub convergence: Option<Angle>,
    /// Multi: one table per camera with `name`, `position`, `rotation` and any `[camera]`
    /// keys to override (deep-merged over `[camera]`).
    pub cameras: Option<Vec<Camera>>,
}

#[derive(JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum RigKind {
    Single,
    Stereo,
    Multi,
}

/// `[[lights]]` — one light. Which keys apply depends on `type`.
#[derive(JsonSchema, Keys)]
#[schemars(deny_unknown_fields)]
pub struct Light {
    /// Light name. **Default:** `"light<i>"`.
    pub name: Option<String>,
    /// Light kind. **Default:** `"spot"`.
    #[serde(rename = "type")]
    pub kind: Option<LightKindName>,
    /// Frame of `position`/`aim`/`target`: the rig (moves with the cameras; camera axes x
    /// right, y down, z forward) or the world. **Default:** `"rig"` for spot/strobe/point,
    /// `"world"` for area/ambient.
    pub mount: Option<MountKind>,
    /// Position. **Unit:** m. **Default:** `[0, 0, 0]`.
    pub position: Option<Vec3<Length>>,
    /// Spot/area: direction the light points (any length). **Unit:** 1. **Default:**
    /// forward (rig `[0, 0, 1]`) or down (world `[0, 0, -1]`).
    pub aim: Option<Vec3<Number>>,
    /// Spot/area: a point to aim at (instead of `aim`). **Unit:** m.
    pub target: Option<Vec3<Length>>,
    /// Spot: full cone angle. **Unit:** rad. **Default:** 100°.
    pub beam_angle: Option<Angle>,
    /// Spot/point: electrical-equivalent radiant power, I = P/4π; area: emitted power,
    /// L = P/(π·A). **Unit:** W (per channel). **Default:** 10 W (spot/point).
    pub power: Option<PerChannel<Power>>,
    /// Spot/point: radiant intensity instead of `power`. **Unit:** W/sr per channel.
    pub intensity: Option<PerChannel<Intensity>>,
    /// Area/ambient: radiance instead of `power`. **Unit:** W/(m²·sr) per channel.
    /// **Default:** 1 (area), 0.1 (ambient).
    pub radiance: Option<PerChannel<Radiance>>,
    /// Colour multiplier per channel. **Unit:** 1. **Default:** `[1, 1, 1]`.
    pub color: Option<PerChannel<Number>>,
    /// Area: width. **Unit:** m. **Default:** 0.5 m.
    pub width: Option<Length>,
    /// Area: height. **Unit:** m. **Default:** 0.5 m.
    pub height: Option<Length>,
}

#[derive(JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum LightKindName {
    /// Cone of `beam_angle` (strobe, video light).
    Spot,
    /// Same as `spot`.
    Strobe,
    /// Isotropic point light.
    Point,
    /// One-sided rectangle emitting along `aim`.
    Area,
    /// Uniform radiance from every direction.
    Ambient,
}

#[derive(JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum MountKind {
    Rig,
    World,
}

/// `[[objects]]` — one piece of geometry. Which keys apply depends on `shape`.
#[derive(JsonSchema, Keys)]
#[schemars(deny_unknown_fields)]
pub struct Object {
    /// Object name. **Default:** `"object<i>"`.
    pub name: Option<String>,
    /// Shape. **Default:** `"box"`.
    pub shape: Option<ShapeKind>,
    /// Scenery around the site, not part of it: the sand beyond the modelled seabed, a far
    /// wall. Every backend renders it; the survey planner's coverage, the tie points of
    /// `poser evaluate` and the texture checks leave it out. A 2 km plane under the site keeps
    /// every view on a bottom (docs/column.md, "Views past the seabed"). **Default:** false.
    pub backdrop: Option<bool>,
    /// A clear glass solid instead of a coloured surface: the catalogue glass it is made of
    /// (`"N-BK7"`, `"PMMA"` or `"acrylic"`, `"fused_silica"`, `"sapphire"`). Light reflects and
    /// refracts at its faces (Fresnel, Snell) and crosses it unabsorbed: a tank's window, a
    /// slab, an acrylic block, a ball lens, a rod. A box, a uniformly scaled sphere or a
    /// cylinder scaled alike on x and y only; it takes no `albedo` or `pattern`. Its daylight is
    /// traced, not read from the water column (docs/column.md). See docs/scenes.md, "Glass
    /// objects". **Default:** none (an opaque Lambertian object).
    pub glass: Option<String>,
    /// A box, sphere or cylinder filled with water: a tank, a jar, a flume, a sample of turbid
    /// water. The table takes `[water]`'s keys (`jerlov`, `absorption`, `scattering`, `phase`,
    /// `g`, `ior`, `temperature`, `salinity`, …; not `extent` or `box_half_size`): the object's
    /// faces are the smooth boundary of that water's index (Fresnel, Snell, as `glass`), and
    /// inside it light is absorbed and scattered as in that water. Around it is the scene's
    /// water, or air without `[water]`. Not with `glass`, `albedo` or `pattern`; it may not
    /// hold a camera or a light. See docs/scenes.md, "Filled objects". **Default:** none.
    pub fill: Option<FillTable>,
    /// Mesh: glTF (`.glb`/`.gltf`), OBJ (with its MTL files) or PLY file, relative to the file
    /// that names it. Every file it names (MTL, images, buffers) must be beside it or elsewhere
    /// inside the scene's folder. See `docs/textures.md`, "Textured meshes".
    pub path: Option<String>,
    /// Mesh: take the albedo from the file, its image textures (glTF `baseColorTexture`, MTL
    /// `map_Kd`), material colours (`baseColorFactor`, `Kd`) and vertex colours (PLY); faces
    /// it gives no colour take `albedo`. Images are sRGB, sampled bilinearly at the mipmap
    /// level whose texel is at most half the finest ground sample distance, in every backend.
    /// `false`: one plain `albedo`. **Default:** true when the file has an image texture or
    /// vertex colours.
    pub texture: Option<bool>,
    /// Mesh: subtracted from the file's vertices (in f64, in the file's own units and axes)
    /// before the up axis, `scale` and the pose: the georeferenced point (e.g. UTM easting,
    /// northing, height) that becomes the object's origin. See `docs/textures.md`,
    /// "Georeferenced meshes". **Default:** `[0, 0, 0]`.
    pub offset: Option<Vec3<Number>>,
    /// Mesh: a text file (relative to the file that names it) holding the three numbers of
    /// `offset`, as photogrammetry exports write a model's shift beside it (instead of
    /// `offset`).
    pub offset_file: Option<String>,
    /// Mesh: the file's axis that points up, `"z"` or `"y"` (a Y-up file is turned
    /// `(x, y, z) → (x, −z, y)`), after `offset`. **Default:** the format's own: `"y"` for
    /// glTF, `"z"` for OBJ and PLY.
    pub up_axis: Option<UpAxisKind>,
    /// Plane width / seabed and boulder field extent along x. **Unit:** m. **Default:** 1 m
    /// (plane), 20 m (seabed, boulders).
    pub width: Option<Length>,
    /// Plane height (along y) / cylinder height (along z). **Unit:** m. **Default:** 1 m.
    pub height: Option<Length>,
    /// Seabed and boulder field extent along y. **Unit:** m. **Default:** 20 m.
    pub length: Option<Length>,
    /// Box: side lengths `[x, y, z]`. **Unit:** m. **Default:** `[1, 1, 1]`.
    pub size: Option<Vec3<Length>>,
    /// Sphere, cylinder radius; boulders: mean radius; coral: colony radius (at most 10 m).
    /// **Unit:** m. **Default:** 0.5 m (0.3 m for boulders and corals).
    pub radius: Option<Length>,
    /// Seabed: RMS relief. **Unit:** m. **Default:** 0.1 m.
    pub roughness: Option<Length>,
    /// Seabed: heightfield cell size. **Unit:** m. **Default:** 0.05 m.
    pub resolution: Option<Length>,
    /// Seabed: a list of surveyed points (`id x y z` per line, as a `points_file` target's
    /// `file`, relative to the file that names it) whose heights the seabed passes through:
    /// its large-scale relief is the thin-plate spline through them (the smoothest surface
    /// through the points), and `roughness` is added on top. 3 to 200 points, not all on one
    /// line. See docs/scenes.md, "A seabed through surveyed heights". **Default:** none (a
    /// flat seabed under its roughness).
    pub relief_file: Option<String>,
    /// Seabed: where the origin of `relief_file`'s frame lies in the world, as a `points_file`
    /// target's `position` (one file, one frame: a GCP list can shape the seabed and print
    /// its disks). **Unit:** m. **Default:** `[0, 0, 0]`.
    pub relief_origin: Option<Vec3<Length>>,
    /// Boulders: how many. **Default:** 30.
    pub count: Option<u32>,
    /// Coral: growth form, `"branching"` (staghorn-like branches of branches) or `"massive"`
    /// (a lumpy, grooved dome, brain-like). The colony stands on the object's xy plane, its
    /// base buried below it. **Default:** `"branching"`.
    pub growth: Option<CoralGrowthKind>,
    /// Seabed, boulders, coral: random seed of the shape. **Default:** `site.seed` + the
    /// object's index.
    pub seed: Option<u64>,
    /// Position of the object's origin (world). **Unit:** m. **Default:** `[0, 0, 0]`;
    /// seabed and boulders: `[0, 0, -site.depth]`.
    pub position: Option<Vec3<Length>>,
    /// Orientation as rotations about x, y, z (x first). **Unit:** rad. **Default:** 0.
    pub rotation: Option<Vec3<Angle>>,
    /// Turn the object's +z axis towards this world point (instead of `rotation`).
    /// **Unit:** m.
    pub look_at: Option<Vec3<Length>>,
    /// Scale factor (one value or `[x, y, z]`). **Unit:** 1. **Default:** 1.
    pub scale: Option<PerChannel<Number>>,
    /// Lambertian albedo in [0, 1]. **Unit:** 1 per channel. **Default:** 0.3.
    pub albedo: Option<PerChannel<Number>>,
    pub pattern: Option<PatternTable>,
}

#[derive(JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ShapeKind {
    Mesh,
    Plane,
    Box,
    Sphere,
    Cylinder,
    Seabed,
    Boulders,
    /// A procedural coral colony (see `growth`, `radius`, `seed`).
    Coral,
}

#[derive(JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum UpAxisKind {
    Z,
    Y,
}

#[derive(JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum CoralGrowthKind {
    Branching,
    Massive,
}

/// `pattern = { … }` — procedural texture modulating an object's albedo. Lengths are physical
/// (object frame, after scale). Every pattern but `checker` is baked into an image texture
/// whose texels are half the finest ground sample distance of the cameras on the object, so
/// that texture exists down to the pixel; the same texture is used by every backend. See
/// `docs/textures.md`.
#[derive(JsonSchema, Keys)]
#[schemars(deny_unknown_fields)]
pub struct PatternTable {
    /// Pattern kind: `"checker"`, `"noise"`, `"fbm"` (fractal albedo), `"sand"` (ripples and
    /// grains), `"rock"` (mottling, cracks, speckle) or `"coral"` (patchy growth colours).
    /// **Default:** `"noise"`.
    #[serde(rename = "type")]
    pub kind: Option<String>,
    /// Checker square; noise feature; fbm largest feature; rock mottling; coral colony size.
    /// **Unit:** m. **Default:** 0.1 m (checker, noise), 1 m (fbm), 0.5 m (rock), 0.3 m (coral).
    pub size: Option<Length>,
    /// Checker: dark squares are albedo × contrast (**Default:** 0.5). Other patterns: RMS
    /// relative albedo variation, 0..1 (**Default:** 0.3 fbm, 0.2 sand, 0.25 rock, 0.2 coral).
    /// **Unit:** 1.
    pub contrast: Option<Number>,
    /// Noise amplitude (0..1). **Unit:** 1. **Default:** 0.5.
    pub amount: Option<Number>,
    /// Random seed of the pattern. **Default:** 0.
    pub seed: Option<u64>,
    /// Fbm: smallest feature (0: down to the texel). **Unit:** m. **Default:** 0.
    pub smallest: Option<Length>,
    /// Fbm: amplitude ratio of successive octaves, 0..1 (0.5: smooth, 0.8: rough).
    /// **Unit:** 1. **Default:** 0.7.
    pub gain: Option<Number>,
    /// Sand: ripple wavelength (0: no ripples). **Unit:** m. **Default:** 0.1 m.
    pub wavelength: Option<Length>,
    /// Sand: direction of the ripples' wave vector (across the crests), from +x towards +y.
    /// **Unit:** rad. **Default:** 0.
    pub direction: Option<Angle>,
    /// Sand: relative albedo swing between ripple troughs (darker) and crests, 0..1.
    /// **Unit:** 1. **Default:** 0.15.
    pub ripple: Option<Number>,
    /// Sand: grain size. **Unit:** m. **Default:** 0.5 mm.
    pub grain: Option<Length>,
    /// Rock: crack spacing (0: no cracks). **Unit:** m. **Default:** 0.2 m.
    pub crack: Option<Length>,
    /// Rock: crack width. **Unit:** m. **Default:** 3 mm.
    pub crack_width: Option<Length>,
    /// Rock: mineral speckle grain size (0: none). **Unit:** m. **Default:** 2 mm.
    pub speckle: Option<Length>,
    /// Coral: fraction of the surface covered by growth, 0..1. **Unit:** 1. **Default:** 0.6.
    pub cover: Option<Number>,
    /// Coral: growth colours, a list of albedos `[r, g, b]`. **Default:** pink-purple, ochre,
    /// olive and pale.
    pub colors: Option<Vec<PerChannel<Number>>>,
    /// Coral: polyp size (0: none). **Unit:** m. **Default:** 5 mm.
    pub polyp: Option<Length>,
    /// Colour variation between objects and between the rocks of a boulder field: relative
    /// brightness and hue jitter, 0..1. **Unit:** 1. **Default:** 0.
    pub variation: Option<Number>,
    /// Texel size of the baked texture. **Unit:** m. **Default:** half the finest ground
    /// sample distance of the scene's cameras on the object (coarsened to keep every baked texture of the scene within 16 Mi texels together and
    /// 8192 texels a side; `poser explain` says by how much).
    pub texel: Option<Length>,
    /// A survey grid drawn over the pattern (strings or tapes along the object's x and y axes,
    /// as on an excavation): line spacing. Not with `checker`. **Unit:** m. **Default:** none.
    pub grid: Option<Length>,
    /// Width of the grid's lines. **Unit:** m. **Default:** 1 cm.
    pub grid_width: Option<Length>,
    /// Albedo of the grid's lines. **Unit:** 1. **Default:** [0.8, 0.75, 0.5] (a pale yellow
    /// string).
    pub grid_albedo: Option<PerChannel<Number>>,
}

/// `[[targets]]` — a calibration target, scale bar or GSD target with known 3D points (ids
/// `name/index`, or code numbers for coded targets). The printed face is the target's
/// z = 0 plane, facing +z.
#[derive(JsonSchema, Keys)]
#[schemars(deny_unknown_fields)]
pub struct Target {
    /// Target name (unique). **Default:** `"target<i>"`.
    pub name: Option<String>,
    /// Target kind. **Default:** `"checkerboard"`.
    #[serde(rename = "type")]
    pub kind: Option<TargetKindName>,
    /// Checkerboard, circle grid: columns (squares / disks). **Default:** 9 / 7.
    pub cols: Option<u32>,
    /// Checkerboard, circle grid: rows. **Default:** 6 / 5.
    pub rows: Option<u32>,
    /// Checkerboard: square side. **Unit:** m. **Default:** 40 mm.
    pub square: Option<Length>,
    /// Circle grid, coded: centre spacing. **Unit:** m. **Default:** 50 mm / 100 mm.
    pub spacing: Option<Length>,
    /// Disk diameter (circle grid, coded, scale bar, test object, points file) or star
    /// diameter. **Unit:** m. **Default:** 20 mm (200 mm for a Siemens star, 100 mm for a
    /// points file).
    pub diameter: Option<Length>,
    /// Points file: the list of `id x y z` (metres; spaces, tabs or commas; `#` comments;
    /// an optional header line), relative to this scene file. Each point becomes a disk
    /// target named `name/id` whose point id is `name/id`. Required for `points_file`.
    pub file: Option<String>,
    /// Points file: where the disks are printed. `"given"`: at the file's coordinates in the
    /// target's frame (`position`, `rotation`), facing its +z. `"seabed"`: each point dropped
    /// straight down onto the scene's objects, facing the surface it lands on, 1 mm above it
    /// (the nominal seabed where there is no object). **Default:** `"given"`.
    pub surface: Option<PointsSurface>,
    /// Coded: number of targets. **Default:** 12.
    pub count: Option<u32>,
    /// Coded: code number of the first target. **Default:** 1.
    pub first_code: Option<u32>,
    /// Scale bar: distance between the two disk centres. **Unit:** m. **Default:** 1 m.
    pub length: Option<Length>,
    /// Scale bar: bar width. **Unit:** m. **Default:** 40 mm.
    pub width: Option<Length>,
    /// Siemens star: number of black sectors. **Default:** 16.
    pub spokes: Option<u32>,
    /// Test object: base width. **Unit:** m. **Default:** 0.5 m.
    pub size: Option<Length>,
    /// Test object: number of steps. **Default:** 3.
    pub levels: Option<u32>,
    /// Test object: step height. **Unit:** m. **Default:** 50 mm.
    pub step: Option<Length>,
    /// Centre of the target (world). **Unit:** m. **Default:** `[0, 0, 0]`.
    pub position: Option<Vec3<Length>>,
    /// Orientation as rotations about x, y, z (x first). **Unit:** rad. **Default:** 0
    /// (face up).
    pub rotation: Option<Vec3<Angle>>,
    /// Turn the printed face towards this world point (instead of `rotation`). **Unit:** m.
    pub look_at: Option<Vec3<Length>>,
}

#[derive(JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum TargetKindName {
    Checkerboard,
    CircleGrid,
    Coded,
    ScaleBar,
    SiemensStar,
    TestObject,
    /// A laboratory's test field or GCP layout from a file: `file`, `diameter`, `surface`.
    PointsFile,
}

#[derive(JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum PointsSurface {
    Given,
    Seabed,
}

/// `[network]` — where the images are taken. Which keys apply depends on `type`.
#[derive(JsonSchema, Keys)]
#[schemars(deny_unknown_fields)]
pub struct Network {
    /// Network kind. **Default:** `"explicit"`.
    #[serde(rename = "type")]
    pub kind: Option<NetworkKind>,
    /// Swim speed along the path. **Unit:** m/s. **Default:** the diver's speed, else 0.2.
    pub speed: Option<Speed>,
    /// Explicit: one `[[network.poses]]` table per rig position.
    pub poses: Option<Vec<PoseTable>>,
    /// Lawnmower, spiral: centre `[x, y]` (or `[x, y, z]`); orbit: the point looked at.
    /// **Unit:** m. **Default:** `[0, 0]` (orbit: `[0, 0, -site.depth]`).
    pub center: Option<List<Length>>,
    /// Lawnmower: area extent across the strips. **Unit:** m. **Default:** 10 m.
    pub width: Option<Length>,
    /// Lawnmower: area extent along the strips. **Unit:** m. **Default:** 10 m.
    pub length: Option<Length>,
    /// Lawnmower: strip direction, clockwise from north. **Unit:** rad. **Default:** 0.
    pub heading: Option<Angle>,
    /// Lawnmower, spiral: camera height above the seabed (or give `gsd`). **Unit:** m.
    pub altitude: Option<Length>,
    /// Lawnmower, spiral: wanted nadir GSD through the port (instead of `altitude`).
    /// **Unit:** m/px.
    pub gsd: Option<Gsd>,
    /// Lawnmower, spiral: forward overlap. **Unit:** fraction. **Default:** 0.8.
    pub overlap: Option<Fraction>,
    /// Lawnmower, spiral: side-lap between strips (< 0.6 gives a warning). **Unit:**
    /// fraction. **Default:** 0.6.
    pub sidelap: Option<Fraction>,
    /// Lawnmower: number of strips. **Default:** from `sidelap`.
    pub strips: Option<u32>,
    /// Lawnmower: add a perpendicular pass. **Default:** false.
    pub cross_strips: Option<bool>,
    /// Lawnmower: oblique tilt forward from nadir. **Unit:** rad. **Default:** 0.
    pub tilt: Option<Angle>,
    /// Lawnmower: fly every strip a second time with the camera tilted forward by this angle
    /// (strips alternate direction, so the obliques look both ways along the strips); the
    /// standard way to decorrelate a self-calibration from the network. **Unit:** rad.
    /// **Default:** none.
    pub obliques: Option<Angle>,
    /// All networks: a hand-held camera's wobble. Every pose is moved by this σ per axis,
    /// seeded by `jitter_seed`. A perfectly regular nadir network is degenerate for
    /// self-calibration (focal length and depth trade off exactly); real surveys are not.
    /// **Unit:** m. **Default:** 0.
    pub jitter_position: Option<Length>,
    /// All networks: every pose is turned by this σ about a random axis. **Unit:** rad.
    /// **Default:** 0.
    pub jitter_rotation: Option<Angle>,
    /// All networks: seed of the jitter. **Default:** 1.
    pub jitter_seed: Option<u64>,
    /// Lawnmower, spiral: `"overlap"` (spacing from `overlap`), a distance (`"0.5 m"`) or a
    /// time (`"2 s"`). **Default:** `"overlap"`.
    pub trigger: Option<String>,
    /// Spiral: outer radius; orbit: horizontal ring radius. **Unit:** m. **Default:** 5 m
    /// (spiral), 2 m (orbit).
    pub radius: Option<Length>,
    /// Orbit: ring elevations above the horizontal plane through `center`. **Unit:** rad.
    /// **Default:** `"20, 45 deg"`.
    pub elevations: Option<List<Angle>>,
    /// Orbit: images per ring. **Default:** 24.
    pub per_ring: Option<u32>,
}

#[derive(JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum NetworkKind {
    /// Poses listed one by one in `[[network.poses]]`.
    Explicit,
    /// Parallel strips over a rectangle, optional cross strips.
    Lawnmower,
    /// Planar Archimedean spiral.
    Spiral,
    /// Rings around an object.
    Orbit,
}

/// `[[network.poses]]` — one explicit rig position.
#[derive(JsonSchema, Keys)]
#[schemars(deny_unknown_fields)]
pub struct PoseTable {
    /// Entrance-pupil position of the rig (world). **Unit:** m. **Required.**
    pub position: Option<Vec3<Length>>,
    /// Point the optical axis at this world point. **Unit:** m. **Default:** straight down.
    pub look_at: Option<Vec3<Length>>,
    /// Up hint for `look_at` (image up is as close to it as possible). **Unit:** 1.
    /// **Default:** `[0, 0, 1]`.
    pub up: Option<Vec3<Number>>,
    /// Orientation `world_from_rig` as rotations about x, y, z (instead of `look_at`;
    /// 0 = looking up the world z axis). **Unit:** rad.
    pub rotation: Option<Vec3<Angle>>,
}

/// `[diver]` — the diver (or vehicle) for planning and dive safety.
#[derive(JsonSchema, Keys)]
#[schemars(deny_unknown_fields)]
pub struct Diver {
    /// Swim speed during the survey. **Unit:** m/s. **Default:** 0.2 m/s.
    pub speed: Option<Speed>,
    /// Descent rate. **Unit:** m/s. **Default:** 18 m/min.
    pub descent_rate: Option<Speed>,
    /// Ascent rate. **Unit:** m/s. **Default:** 9 m/min.
    pub ascent_rate: Option<Speed>,
    /// Surface air consumption. **Unit:** m³/s (write `"20 l/min"`). **Default:** 20 l/min.
    pub sac: Option<Flow>,
    /// Bühlmann gradient factor low. **Unit:** fraction (`0.3` or `"30 %"`). **Default:** 0.3.
    pub gf_low: Option<Fraction>,
    /// Bühlmann gradient factor high. **Unit:** fraction. **Default:** 0.75 (with `gf_low`
    /// 0.3: Subsurface's default GF 30/75).
    pub gf_high: Option<Fraction>,
    /// Gas that must remain in every cylinder at the surface. **Unit:** Pa (write
    /// `"50 bar"`). **Default:** 50 bar.
    pub reserve: Option<Pressure>,
    /// Highest pO₂ of bottom and stage gases (sets their MOD). **Unit:** Pa (write
    /// `"1.4 bar"`). **Default:** 1.4 bar (Subsurface).
    pub po2_bottom: Option<Pressure>,
    /// Highest pO₂ of deco gases (sets their default switch depth). **Unit:** Pa (write
    /// `"1.6 bar"`). **Default:** 1.6 bar (Subsurface).
    pub po2_deco: Option<Pressure>,
    /// Deepest equivalent narcotic depth (END) of a gas the planner names: its gas advice
    /// adds helium (trimix) to keep the END within it, and the report flags a breathed gas
    /// beyond it. O₂ counts as narcotic (Subsurface's default; GUE, TDI, IANTD), the
    /// conservative choice. **Unit:** m (0 < END ≤ 100 m). **Default:** 30 m.
    pub end_limit: Option<Length>,
    /// `"none"`: a no-decompression dive, one that needs stops is NOT SAFE AS PLANNED;
    /// `"planned"`: decompression is planned and accepted, and a dive whose whole plan holds
    /// (the stops on the gases carried, every gas where it is breathed, the gas rules, CNS and
    /// pO₂, the lost-gas plans) is "OK, decompression planned". **Default:** `"none"`.
    pub deco: Option<String>,
    /// `"salt"` (1030 kg/m³, Subsurface's sea water) or `"fresh"` (1000 kg/m³).
    /// **Default:** `"salt"`.
    pub water: Option<String>,
    /// Cylinders carried: `[[diver.cylinders]]`. **Default:** one 12 l, 200 bar of air.
    pub cylinders: Option<Vec<CylinderTable>>,
}

/// `[[diver.cylinders]]` — one cylinder.
#[derive(JsonSchema, Keys)]
#[schemars(deny_unknown_fields)]
pub struct CylinderTable {
    /// Cylinder name. **Default:** `"cylinder<i>"`.
    pub name: Option<String>,
    /// Water volume. **Unit:** m³ (write `"12 l"`). **Default:** 12 l.
    pub volume: Option<Volume>,
    /// Fill pressure. **Unit:** Pa (write `"232 bar"`). **Default:** 200 bar.
    pub pressure: Option<Pressure>,
    /// Gas: `"air"` (20.9 % O₂, as Subsurface), `"EAN32"`/`"nitrox32"`, `"TX18/45"` (trimix
    /// O₂/He), `"O2"`. **Default:** `"air"`.
    pub gas: Option<String>,
    /// O₂ fraction (overrides `gas`). **Unit:** fraction.
    pub o2: Option<Fraction>,
    /// He fraction (overrides `gas`). **Unit:** fraction.
    pub he: Option<Fraction>,
    /// `"bottom"` (back gas, breathed on the bottom; from the surface unless a travel gas
    /// carries the diver down), `"stage"` (bottom gas breathed first, down to the reserve),
    /// `"travel"` (breathed on the descent from the surface to `switch_depth`, where the
    /// bottom gas takes over, and on the ascent from `switch_depth` up), `"deco"` (breathed on
    /// the ascent from `switch_depth`) or `"bailout"` (not breathed in the plan: carried for
    /// the loss of the bottom gas, and checked by the plan of that ascent).
    /// **Default:** `"bottom"` for the first cylinder; later ones `"deco"` when richer in O₂
    /// than the first, else `"bottom"`.
    pub role: Option<String>,
    /// Travel or deco gas: the depth down to which a travel gas is breathed on the descent,
    /// and from which a travel or deco gas is breathed on the ascent. **Unit:** m.
    /// **Default:** a deco gas's MOD at `diver.po2_deco`; a travel gas's deepest depth within
    /// `diver.po2_bottom` and `diver.end_limit`; both rounded down to whole metres.
    pub switch_depth: Option<Length>,
}

/// `[render]` — render settings shared by every backend (image size is on `[camera]`).
#[derive(JsonSchema, Keys)]
#[schemars(deny_unknown_fields)]
pub struct Render {
    /// Samples per pixel (≥ 1). **Default:** 64.
    pub samples: Option<u32>,
    /// Seed of the renderers' random choices (samples, the column's photons, sensor noise); it
    /// changes the noise, never the site (that is `site.seed`). **Default:** 0.
    pub seed: Option<u64>,
    /// Most scattering vertices (surface or medium) on a path. **Default:** 8, raised to what
    /// keeps 99 % of the daylight the cameras see where the scene's water is a column whose
    /// light has scattered more often (measured on the column, docs/column.md; at most 254).
    /// At least 1 (0 would end every path at its first surface: error E0046). A written value
    /// that cuts off more than 1 % is warning W0239, with the share.
    pub bounces: Option<u32>,
    /// Render one pass per channel with that channel's indices (only done when the lateral
    /// colour is ≥ 0.1 px). **Default:** false.
    pub dispersion: Option<bool>,
    /// Outputs wanted: any of `"rgb"`, `"depth"`, `"truth"`. **Default:** all three.
    pub outputs: Option<Vec<String>>,
    /// Exposure multiplier for the PNG preview (EXR stays linear). **Unit:** 1.
    /// **Default:** 1.
    pub exposure: Option<Number>,
    /// Native renderer: `"illumination"` also writes `<image>.denoised.exr`, the render with
    /// its illumination (radiance ÷ first-hit albedo) smoothed across neighbouring pixels at
    /// the same depth and the albedo multiplied back: texture stays sharp, shadow edges soften
    /// by about `denoise_radius`. The PNG preview and the sensor stage then use it; the `.exr`
    /// stays the unfiltered render (`docs/native.md`). **Default:** `"none"`.
    pub denoise: Option<String>,
    /// Gaussian radius of the illumination denoiser (σ). **Unit:** px. **Default:** 2.
    pub denoise_radius: Option<Number>,
    /// Native renderer: a noise target, the relative standard error of each pixel's mean
    /// (e.g. `"2 %"`), or `"sensor"`: no more than the sensor's own noise (shot and read
    /// noise) at each pixel, at the exposure the sensor stage picks (needs `[sensor]` or
    /// `--sensor`). Every pixel first takes `samples` samples as a pilot, then as many fresh
    /// ones as its pilot says it needs (up to `max_samples`); the pilot is dropped, so the
    /// mean stays unbiased. Writes `<image>.noise.json` with the samples taken and the noise
    /// achieved (`docs/native.md`). **Unit:** fraction, or `"sensor"`. **Default:** none
    /// (`samples` everywhere).
    pub noise: Option<NoiseGoal>,
    /// With `noise`: the most samples a pixel takes after its pilot. **Default:** 16 ×
    /// `samples`.
    pub max_samples: Option<u32>,
    /// Native renderer: how daylight reaches the scene through the water. `"column"` solves
    /// the plane-parallel water column once (sun, sky, scattering, seabed) and lights the
    /// scene with it, tracing only the scene's own geometry, strobes and the sun's first
    /// scattering: far less noise for the same samples. `"traced"` random-walks the light
    /// through the water, as Mitsuba and Cycles do. `"auto"` takes the column where it applies
    /// (water everywhere below the surface, absorbing and scattering, lit by sun or sky) and
    /// every camera's view ends on the scene's seabed (a view past its edge into bottomless
    /// water keeps daylight traced: give the site a `backdrop` plane); `poser explain` says
    /// which, and why. **Default:** `"auto"` (`docs/column.md`).
    pub daylight: Option<String>,
    /// Native renderer: how textures are read where a camera ray first meets a surface.
    /// `"footprint"` averages the texture over the patch the pixel sees there (mip levels,
    /// trilinear), so the texture adds no noise within a pixel and cannot alias;
    /// `"point"` reads it at the hit, one bilinear lookup per sample (the samples average the
    /// pixel, as Mitsuba and Cycles do). Same image mean; `"point"` is for comparison.
    /// **Default:** `"footprint"` (`docs/textures.md`).
    pub texture_filter: Option<String>,
    /// Native renderer: the sea surface seen from below. `"fresnel"`: a flat or wavy surface
    /// reflects the light coming up to it (unpolarised Fresnel, all of it beyond the critical
    /// angle, about 48.6° from the vertical) and the sky is seen through Snell's window, as
    /// under a real sea. `"open"`: the light coming up leaves, and the sky is an isotropic
    /// radiance below the surface, as Mitsuba and Cycles have it (`poser explain` prints how
    /// far apart the two are on the scene's column). **Default:** `"fresnel"`
    /// (`docs/column.md`).
    pub surface_from_below: Option<String>,
    /// Native renderer: the random numbers of a pixel's samples. `"sobol"`: the first 132
    /// draws of every sample (the camera ray, its first vertex and first bounces) come from an
    /// Owen-scrambled Sobol sequence over the pixel's samples, so the samples stratify each
    /// other and the pixel's mean converges faster; `"independent"`: every draw is
    /// independent. Both are unbiased and deterministic for a seed, at any thread count.
    /// **Default:** `"sobol"` (`docs/native.md`, "The sampler").
    pub sampler: Option<String>,
}

/// `[sensor]` — the camera after the lens: exposure, photon shot noise, read noise, ADC, white
/// balance, tone curve and the 8-bit file a camera writes (`OUT/camera/<image>.jpg|png` beside
/// the linear EXR, with `<image>.sensor.json`). Optional: without it `poser render` writes only
/// the linear EXR and its preview. Model, units and formulas: `docs/sensor.md`.
#[derive(JsonSchema, Keys)]
#[schemars(deny_unknown_fields)]
pub struct Sensor {
    /// Full-well capacity: electrons a pixel holds before it saturates. **Unit:** e⁻.
    /// **Default:** 15000.
    pub full_well: Option<Number>,
    /// Read noise (temporal dark noise), RMS. **Unit:** e⁻. **Default:** 3.
    pub read_noise: Option<Number>,
    /// Quantum efficiency per channel (electrons per photon) at the channel wavelengths.
    /// **Unit:** fraction. **Default:** [0.45, 0.55, 0.45].
    pub quantum_efficiency: Option<PerChannel<Fraction>>,
    /// Bits of the analogue-to-digital converter (8 to 16). **Default:** 12.
    pub bits: Option<u32>,
    /// Black level (offset added before the ADC so negative read noise is not clipped).
    /// **Unit:** DN. **Default:** 2^bits / 64.
    pub black_level: Option<u32>,
    /// ISO speed (analogue gain): at `base_iso` the full well fills the ADC; ISO `s` needs
    /// `base_iso / s` of it. **Default:** 100.
    pub iso: Option<Number>,
    /// ISO at which the full well just fills the ADC. **Default:** 100.
    pub base_iso: Option<Number>,
    /// `"auto"`: the shutter time is chosen on the image (`meter`, `percentile`, `target`);
    /// `"manual"`: `shutter` is used as given. **Default:** `"auto"`.
    pub exposure: Option<String>,
    /// Exposure time (manual exposure; the fallback of auto exposure on a black image).
    /// **Unit:** s. **Default:** 8 ms.
    pub shutter: Option<Duration>,
    /// Aperture f-number for the exposure. **Default:** the camera's `f_number`, else 8.
    pub f_number: Option<Number>,
    /// Transmittance of the lens and port glass to the sensor. **Unit:** fraction.
    /// **Default:** 0.9.
    pub transmittance: Option<Fraction>,
    /// Auto-exposure metering: `"highlights"` puts the `percentile` of the brightest
    /// white-balanced channel at `target` of full scale; `"average"` puts the mean luminance
    /// at `target`. **Default:** `"highlights"`.
    pub meter: Option<String>,
    /// Percentile metered by `"highlights"`. **Unit:** fraction. **Default:** 99 %.
    pub percentile: Option<Fraction>,
    /// Metered level as a fraction of the ADC's full scale. **Unit:** fraction.
    /// **Default:** 85 % (`"highlights"`), 18 % (`"average"`).
    pub target: Option<Fraction>,
    /// White balance: `"grey_world"` (channel means equalised on the image, gains at most 8),
    /// `"none"`, or fixed gains `[r, g, b]`. **Default:** `"grey_world"`.
    pub white_balance: Option<WhiteBalanceValue>,
    /// Tone curve from linear to the file: `"srgb"` (IEC 61966-2-1), `"gamma"` (`gamma`) or
    /// `"linear"`. **Default:** `"srgb"`.
    pub tone: Option<String>,
    /// Exponent of the `"gamma"` curve (`v = x^(1/gamma)`). **Default:** 2.2.
    pub gamma: Option<Number>,
    /// File written: `"jpeg"` or `"png"` (8 bits per channel). **Default:** `"jpeg"`.
    pub format: Option<String>,
    /// JPEG quality, 1 to 100. **Default:** 95.
    pub quality: Option<u32>,
    /// Photon shot noise and read noise on (`false`: a noiseless camera, for checks).
    /// **Default:** true.
    pub noise: Option<bool>,
}

/// `[lesson]` — makes the scene a lesson that `poser lesson` runs into one HTML page
/// (`docs/lessons.md`). Ignored by every other command.
#[derive(JsonSchema, Keys)]
#[schemars(deny_unknown_fields)]
pub struct LessonTable {
    /// Title of the page. **Default:** the scene name.
    pub title: Option<String>,
    /// The question the lesson answers (required).
    pub question: Option<String>,
    /// The set-up in a sentence or two. **Default:** the scene description.
    pub setup: Option<String>,
    /// What this shows: the lesson's answer in two or three plain sentences, opening the page
    /// (every shipped lesson has one). **Default:** none.
    pub shows: Option<String>,
    /// What is measured: `"deformation"` (`poser evaluate` on each variant: the bowl),
    /// `"calibration"` (native renders of a board, OpenCV calibration per variant),
    /// `"contrast"` (native renders of the first target at `gsd`: contrast, colour cast,
    /// backscatter), `"gsd"` (the camera height for `gsd` through the exact port, and the
    /// smallest resolved Siemens-star element), `"dive"` (`poser plan` and `poser dive` per
    /// variant: deco, gas, verdict, dives needed), `"survey"` (as `"dive"`, plus `poser
    /// evaluate` with the targets as GCPs), `"completeness"` (the share of the corals'
    /// surface seen by at least 3 images within 60° of its normal) or `"metrology"` (a
    /// stereo rig: backscatter and contrast on the first target, a checkerboard, and `poser
    /// evaluate --rig --gcp`) or `"surface"` (a camera above the water: how far the waves
    /// move the targets in the image, and the caustics' contrast from 1 to 10 m down).
    /// **Default:** `"deformation"`.
    pub kind: Option<LessonKindValue>,
    /// Kinds `contrast` and `gsd`: the ground sampling distance at the first target's centre
    /// for which the camera is placed (exact projection through the port). **Unit:** m/px.
    pub gsd: Option<Gsd>,
    /// `--set` overrides of the quick form, applied by default (e.g.
    /// `["network.length=10"]`). **Default:** none.
    pub quick: Option<Vec<String>>,
    /// `--set` overrides of the full form (`poser lesson --full`). **Default:** none.
    pub full: Option<Vec<String>>,
    /// The cases compared on the page: `[[lesson.variants]]`. **Default:** the scene itself.
    pub variants: Option<Vec<LessonVariantTable>>,
    /// "Try next" lines: `[[lesson.try_next]]`. **Default:** none.
    pub try_next: Option<Vec<TryNextTable>>,
}

#[derive(JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum LessonKindValue {
    Deformation,
    Calibration,
    Contrast,
    Gsd,
    Dive,
    Survey,
    Completeness,
    Metrology,
    Surface,
}

/// `[[lesson.variants]]` — one compared case.
#[derive(JsonSchema, Keys)]
#[schemars(deny_unknown_fields)]
pub struct LessonVariantTable {
    /// Label on the page. **Default:** `"variant <i>"`.
    pub label: Option<String>,
    /// Scene file of this case, relative to the file that names it. **Default:** the lesson's
    /// own scene.
    pub scene: Option<String>,
    /// `--set` overrides applied to that scene. **Default:** none.
    pub set: Option<Vec<String>>,
}

/// `[[lesson.try_next]]` — a suggestion: a sentence and the one override that does it.
#[derive(JsonSchema, Keys)]
#[schemars(deny_unknown_fields)]
pub struct TryNextTable {
    /// What to try (required).
    pub text: Option<String>,
    /// The `--set KEY=VALUE` that changes that one thing (required).
    pub set: Option<String>,
}

/// A noise target: a relative standard error (a fraction) or `"sensor"`.
#[derive(JsonSchema)]
#[serde(untagged)]
pub enum NoiseGoal {
    Relative(Fraction),
    Sensor(String),
}

/// A white balance: a mode name or fixed gains `[r, g, b]`.
#[derive(JsonSchema)]
#[serde(untagged)]
pub enum WhiteBalanceValue {
    Mode(String),
    Gains([f64; 3]),
}

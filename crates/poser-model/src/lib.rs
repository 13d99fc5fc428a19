//! The resolved model: the one explicit structure every backend consumes.
//!
//! A scene file (see `poser::scene`) is parsed, validated and *resolved* into a [`Model`]:
//! SI units everywhere, every preset, include and command-line override applied, camera
//! networks expanded into poses, and optical constants computed per colour channel. The model
//! also records what the scene *needs* ([`Needs`]) so that backends emit only that.
//!
//! Conventions (shared by every module):
//! * World frame: right-handed, metres, **z up**, x east, y north. The sea surface (if any) is
//!   the plane z = 0; the nominal seabed of the site is z = -`site.depth`.
//! * Camera frame: OpenCV — x right, y down, z forward; origin at the entrance pupil.
//! * Pixel (i, j) covers [i, i+1]×[j, j+1]; its centre is (i+0.5, j+0.5): COLMAP's
//!   convention. OpenCV's pixel centres are at integers (subtract 0.5).
//! * Rotations are stored as `DMat3` whose columns are the child axes in the parent frame
//!   (`parent_from_child`), so `p_parent = R * p_child + t`.
//! * Colour channels are always `[R, G, B]` at [`CHANNEL_WAVELENGTHS_NM`].
//! * Angles in radians, lengths in metres, times in seconds, pressures in pascal, volumes in m³,
//!   temperatures in °C (the one non-SI exception, as everyone writes them), salinity in PSU.

// `!(x > 0.0)` is how poser rejects NaN together with the values out of range.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod valid;

use glam::DVec3;
use poser_optics::project::Projector;
use serde::{Deserialize, Serialize};

/// Representative wavelengths of the R, G and B channels, in nanometres.
pub const CHANNEL_WAVELENGTHS_NM: [f64; 3] = [650.0, 550.0, 450.0];

pub use poser_optics::types::{Pose, Rgb};

/// The whole resolved scene.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Model {
    /// Scenario name (from the file, or its stem).
    pub name: String,
    /// Free-text description for trainers.
    pub description: String,
    /// Path of the scene file as given (for messages and for resolving relative assets).
    pub source: String,
    /// The water, or `None` for a survey in air (then no medium is emitted anywhere).
    pub water: Option<Water>,
    /// Site: depth, sea surface, seabed.
    pub site: Site,
    /// The sun, if the scene is lit by daylight.
    pub sun: Option<Sun>,
    /// The cameras of the rig, each with its housing port. At least one.
    pub cameras: Vec<Camera>,
    /// Lights other than the sun.
    pub lights: Vec<Light>,
    /// Scene geometry other than targets.
    pub objects: Vec<Object>,
    /// Calibration targets, scale bars, GSD targets; all with known 3D points.
    pub targets: Vec<Target>,
    /// The expanded camera network: one entry per rig position (every camera fires at each).
    pub poses: Vec<RigPose>,
    /// Summary of the network that produced the poses (for planning and `explain`).
    pub network: NetworkSummary,
    /// Diver or vehicle, for planning and dive safety.
    pub diver: Option<Diver>,
    /// Render settings.
    pub render: RenderSettings,
    /// The camera's sensor stage after rendering (`None`: only the linear EXR and its preview).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sensor: Option<Sensor>,
    /// What the scene needs modelled, with reasons.
    pub needs: Needs,
    /// The lesson this scene teaches (`poser lesson`), if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lesson: Option<Lesson>,
}

/// A lesson (`[lesson]`): what `poser lesson` runs and how its page reads (`docs/lessons.md`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Lesson {
    pub title: String,
    pub question: String,
    pub setup: String,
    /// "What this shows": the answer in plain words (may be empty).
    pub shows: String,
    pub kind: LessonKind,
    /// Kinds `contrast` and `gsd`: the GSD (m/px) at the first target the camera is placed for.
    pub gsd: Option<f64>,
    /// `--set` overrides of the quick form (the default) and of the full form (`--full`).
    pub quick: Vec<String>,
    pub full: Vec<String>,
    /// What the page compares; empty: the scene itself.
    pub variants: Vec<LessonVariant>,
    pub try_next: Vec<TryNext>,
}

/// What a lesson measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LessonKind {
    /// `poser evaluate` (observations mode) on each variant: the bowl.
    Deformation,
    /// Native renders of a board, corners detected and calibrated with OpenCV, per variant.
    Calibration,
    /// Native renders of a target at a GSD: Michelson contrast, colour cast, backscatter.
    Contrast,
    /// Camera height for a GSD through the port; smallest resolved Siemens-star element.
    Gsd,
    /// `poser plan` and `poser dive` per variant: deco, gas, verdict, dives needed.
    Dive,
    /// As `Dive`, plus `poser evaluate` (observations mode, GCPs): the expected accuracy.
    Survey,
    /// Surface coverage: the share of the corals' surface seen by enough images, near enough
    /// to its normal (`poser::lesson::completeness`).
    Completeness,
    /// A stereo rig's lighting (backscatter, contrast) and its measurement accuracy (`poser
    /// evaluate` with the rig calibrated) per variant (`poser::lesson::metrology`).
    Metrology,
    /// A camera above the water: how far the waves move targets in the image, and the
    /// caustics' contrast against depth (`poser::lesson::surface`).
    Surface,
}

/// One compared case: a scene file (absolute; `None`: the lesson's own scene) with `--set`
/// overrides.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct LessonVariant {
    pub label: String,
    pub scene: Option<String>,
    pub set: Vec<String>,
}

/// A "try next" line of the page: the text and the one `--set` that changes one thing.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct TryNext {
    pub text: String,
    pub set: String,
}

// ------------------------------------------------------------------------------------------
// Water, site, sun
// ------------------------------------------------------------------------------------------

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Water {
    /// Phase index of the water per channel.
    pub ior: Rgb,
    /// How the index was obtained (for `explain`).
    pub ior_source: IorSource,
    /// Absorption coefficient σa per channel, 1/m.
    pub absorption: Rgb,
    /// Scattering coefficient σs per channel, 1/m.
    pub scattering: Rgb,
    /// Name of the Jerlov type used, if any (`"IB"`, `"3C"`, …).
    pub jerlov: Option<String>,
    pub phase: Phase,
    /// Where the water is.
    pub extent: WaterExtent,
}

impl Water {
    /// Extinction σt = σa + σs per channel, 1/m.
    pub fn extinction(&self) -> Rgb {
        [0, 1, 2].map(|c| self.absorption[c] + self.scattering[c])
    }
    /// Single-scattering albedo σs/σt per channel (0 where σt = 0).
    pub fn albedo(&self) -> Rgb {
        let t = self.extinction();
        [0, 1, 2].map(|c| {
            if t[c] > 0.0 {
                self.scattering[c] / t[c]
            } else {
                0.0
            }
        })
    }
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum IorSource {
    /// Given as a constant by the scene.
    Constant,
    /// Quan–Fry (temperature, salinity, wavelength), with Millard–Seaver pressure correction
    /// when `depth` > 0.
    Seawater {
        temperature: f64,
        salinity: f64,
        depth: f64,
    },
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Phase {
    /// Henyey–Greenstein with asymmetry `g` ∈ (-1, 1).
    HenyeyGreenstein { g: f64 },
    /// Fournier–Forand (Mobley–Sundman–Boss form): real index of particles relative to water
    /// `n` (> 1) and Junge slope `mu` (3 < μ ≤ 5). `backscatter` is the resulting fraction B.
    FournierForand { n: f64, mu: f64, backscatter: f64 },
}

impl Phase {
    /// The optics' phase function for this one, as the renderers and the water column use it:
    /// HG with `g` kept inside (-0.999, 0.999), FF as its table.
    pub fn phase_fn(&self) -> poser_optics::phase::PhaseFn {
        match *self {
            Phase::HenyeyGreenstein { g } => poser_optics::phase::PhaseFn::Hg {
                g: g.clamp(-0.999, 0.999),
            },
            Phase::FournierForand { n, mu, .. } => poser_optics::phase::ff_table(n, mu),
        }
    }
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum WaterExtent {
    /// Water fills all space below the sea surface (or all space when there is no surface).
    Everywhere,
    /// Only an axis-aligned box of the given half-size around each camera position (the
    /// original POSER's trick for fast volumes). Outside it: clear water (index kept, no medium).
    BoxAroundCamera { half_size: DVec3 },
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Site {
    /// Depth of the nominal seabed below the surface, m (> 0 underwater).
    pub depth: f64,
    pub surface: SeaSurface,
    /// Altitude above sea level of the water surface, m (for dive planning at altitude).
    pub altitude: f64,
    /// Seed of the site's generated content: the waves, and the default seed of generated
    /// objects (+ their index). Never `render.seed`: a render's noise does not move the site.
    #[serde(default, skip_serializing_if = "is_default")]
    pub seed: u64,
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum SeaSurface {
    /// No interface is modelled (sunlight, if any, is a directional light in the water).
    None,
    /// A flat air–water interface at z = 0.
    Flat,
    /// A wavy surface: significant wave height (m), dominant wavelength (m), wind speed (m/s).
    Waves {
        height: f64,
        wavelength: f64,
        wind_speed: f64,
    },
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Sun {
    /// Elevation above the horizon, rad.
    pub elevation: f64,
    /// Azimuth, clockwise from north, rad.
    pub azimuth: f64,
    /// Irradiance on a plane normal to the sun, above the surface, W/m² per channel.
    pub irradiance: Rgb,
    /// Unit direction in which sunlight *propagates in air* (world frame; z < 0).
    pub direction_air: DVec3,
    /// Unit direction in which sunlight propagates *in the water* after refraction at a flat
    /// surface (equals `direction_air` when there is no water).
    pub direction_water: DVec3,
    /// Irradiance on a plane normal to `direction_water`, just below the surface, W/m² per
    /// channel: `E_air · T_Fresnel · cos θa / cos θw` (see docs/render-conventions.md §3.3).
    pub irradiance_water: Rgb,
    /// How the sun's position was obtained.
    pub from_time: Option<SunTime>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SunTime {
    pub latitude: f64,
    pub longitude: f64,
    /// ISO-8601 date-time with offset, as given.
    pub datetime: String,
}

// ------------------------------------------------------------------------------------------
// Cameras, lenses, ports: value types of the optics core ([`poser_optics::types`]), re-exported
// here so the model reads as one structure.
// ------------------------------------------------------------------------------------------

pub use poser_optics::types::{Camera, Distortion, Glass, GlassLayer, LensModel, Port};

// ------------------------------------------------------------------------------------------
// Lights
// ------------------------------------------------------------------------------------------

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Light {
    pub name: String,
    /// Whether `position`/`direction` are in the rig frame (moves with the cameras) or world.
    pub mount: Mount,
    pub kind: LightKind,
}

impl Light {
    /// This light as it stands in the world when the rig is at `world_from_rig` (a
    /// world-mounted light unchanged; the result is world-mounted).
    pub fn in_world(&self, world_from_rig: &Pose) -> Light {
        let mut l = self.clone();
        if l.mount == Mount::Rig {
            let w = world_from_rig;
            match &mut l.kind {
                LightKind::Point { position, .. } => *position = w.transform_point(*position),
                LightKind::Spot {
                    position,
                    direction,
                    ..
                } => {
                    *position = w.transform_point(*position);
                    *direction = w.transform_vector(*direction);
                }
                LightKind::Area { frame, .. } => *frame = w.compose(frame),
                LightKind::Ambient { .. } => {}
            }
            l.mount = Mount::World;
        }
        l
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Mount {
    Rig,
    World,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum LightKind {
    /// Isotropic point light. `intensity` in W/sr per channel (Blender power P ↔ I = P/4π).
    Point { position: DVec3, intensity: Rgb },
    /// Spot (strobe, LED): sharp cone of half-angle `half_angle` (rad) about unit `direction`,
    /// uniform `intensity` W/sr inside the cone, zero outside.
    Spot {
        position: DVec3,
        direction: DVec3,
        half_angle: f64,
        intensity: Rgb,
    },
    /// One-sided rectangular area light emitting along its local +z (`frame` columns are
    /// its x, y, z axes), size `width`×`height` m, uniform `radiance` W/(m²·sr).
    Area {
        frame: Pose,
        width: f64,
        height: f64,
        radiance: Rgb,
    },
    /// Uniform radiance arriving from every direction, W/(m²·sr) (a crude stand-in for sky).
    Ambient { radiance: Rgb },
}

// ------------------------------------------------------------------------------------------
// Objects and targets
// ------------------------------------------------------------------------------------------

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Object {
    pub name: String,
    pub shape: Shape,
    /// `world_from_object`; `scale` is applied in the object frame before it.
    pub pose: Pose,
    pub scale: DVec3,
    pub material: Material,
    /// Scenery, not site (`backdrop = true`): rendered everywhere, left out of the planner's
    /// coverage, the evaluation's tie points and the texture checks.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub backdrop: bool,
}

/// The axis of a mesh file that points up (poser's object frame is +Z up).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum UpAxis {
    /// +Z up: taken as it is.
    Z,
    /// +Y up (glTF's convention): `(x, y, z) → (x, −z, y)`.
    Y,
}

fn is_zero(v: &DVec3) -> bool {
    *v == DVec3::ZERO
}

fn is_default<T: Default + PartialEq>(v: &T) -> bool {
    *v == T::default()
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Shape {
    /// Triangle mesh from a glTF, OBJ or PLY file (path resolved, relative to the scene file,
    /// and checked to stay inside the scene's directory tree; see
    /// `poser::geometry::meshfile`).
    Mesh {
        path: String,
        /// The albedo comes from the file: its image textures, material colours and vertex
        /// colours (`poser::texture::mapped`); faces the file gives no colour take the
        /// object's `albedo`. `false`: the object's `albedo` everywhere.
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        textured: bool,
        /// Subtracted from the file's vertices (in the file's own units and axes, in f64)
        /// before anything else: the georeferenced point that becomes the object's origin.
        #[serde(default, skip_serializing_if = "is_zero")]
        offset: DVec3,
        /// Which axis of the file points up; `None`: the format's own (glTF +Y, OBJ and PLY
        /// +Z). Applied after `offset`, before the object's scale and pose
        /// (`poser::geometry::mesh::georeferenced`).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        up_axis: Option<UpAxis>,
    },
    /// Rectangle in the object's xy plane, centred, normal +z.
    Plane {
        width: f64,
        height: f64,
    },
    /// Axis-aligned box, centred.
    Box {
        size: DVec3,
    },
    Sphere {
        radius: f64,
    },
    /// Cylinder along the object's z axis, centred.
    Cylinder {
        radius: f64,
        height: f64,
    },
    /// Procedural seabed: a `width`×`length` heightfield on the object's xy plane, fractal
    /// relief of RMS `roughness` m, `resolution` m cell size, from `seed`; with `relief`
    /// points (object frame, at most 200, not all on one line) the fractal relief is added to
    /// the thin-plate spline through them, the surveyed heights of the site.
    Seabed {
        width: f64,
        length: f64,
        roughness: f64,
        resolution: f64,
        seed: u64,
        #[serde(default, skip_serializing_if = "Vec::is_empty")]
        relief: Vec<DVec3>,
    },
    /// Procedural rock/coral field scattered on the seabed: `count` boulders of mean radius
    /// `radius` within `width`×`length`, from `seed`.
    Boulders {
        width: f64,
        length: f64,
        count: u32,
        radius: f64,
        seed: u64,
    },
    /// Procedural coral colony standing on the object's xy plane (base buried below z = 0):
    /// `growth` form, colony `radius`, from `seed` (`poser::geometry::coral`).
    Coral {
        growth: CoralGrowth,
        radius: f64,
        seed: u64,
    },
}

/// The growth form of a [`Shape::Coral`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CoralGrowth {
    /// Staghorn-like: branches of branches.
    Branching,
    /// Brain-like: a lumpy, grooved dome.
    Massive,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Material {
    /// Lambertian albedo per channel, in [0, 1].
    pub albedo: Rgb,
    /// Optional procedural pattern modulating the albedo.
    pub pattern: Option<Pattern>,
    /// Colour variation between objects (and between the rocks of a boulder field): each part's
    /// albedo is multiplied by a brightness and hue jitter of this relative size, from the
    /// pattern's seed (see `poser::texture`). 0 = none.
    #[serde(default)]
    pub variation: f64,
    /// Texel size of the baked texture, m; `None`: half the finest ground sample distance of
    /// the scene's cameras on this object (see `poser::texture::bake`).
    #[serde(default)]
    pub texel: Option<f64>,
    /// Lines of a survey grid (string or tape) drawn over a baked pattern.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grid: Option<Grid>,
    /// A clear glass solid instead of a Lambertian surface (`glass = "N-BK7"`): a smooth
    /// dielectric boundary (Fresnel reflection and refraction) between the water (or air)
    /// around it and the glass inside, which neither absorbs nor scatters. `albedo` and
    /// `pattern` do not apply.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub glass: Option<Glass>,
    /// A closed object filled with a medium (`fill = { … }`): a tank, a jar, a flume, a fog
    /// box. Its faces are the smooth boundary of the medium's index (`glass` then holds that
    /// index, named `"fill"`), and inside it light is absorbed and scattered as in this water
    /// (its `extent` is the object). `None`: no medium inside.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fill: Option<Water>,
}

/// Lines along the object's x and y axes every `spacing` m, `width` m wide, of albedo `albedo`
/// (a site's grid strings or tapes), baked into the texture over the pattern.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Grid {
    pub spacing: f64,
    pub width: f64,
    pub albedo: Rgb,
}

impl Material {
    /// Whether this material is baked into an image texture (every pattern but the checker,
    /// which every backend draws exactly, or any colour variation).
    pub fn is_baked(&self) -> bool {
        self.variation > 0.0
            || self.grid.is_some()
            || matches!(&self.pattern, Some(p) if !matches!(p, Pattern::Checker { .. }))
    }
}

/// A procedural albedo pattern. Lengths in metres, measured in the object frame after scale;
/// see `docs/textures.md` and `poser::texture` for the formulas.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Pattern {
    /// Checker of square `size` m between albedo and `albedo * contrast` (drawn exactly, not
    /// baked).
    Checker { size: f64, contrast: f64 },
    /// Two-octave value noise of feature `size` m, amplitude `amount` (0..1).
    Noise { size: f64, amount: f64, seed: u64 },
    /// Fractal (fBm) albedo: gradient-noise octaves from `size` down to `smallest` (or to the
    /// texel), each `gain` times the previous amplitude; relative amplitude `contrast`.
    Fbm {
        size: f64,
        smallest: f64,
        gain: f64,
        contrast: f64,
        seed: u64,
    },
    /// Sand: ripples of `wavelength` m with crests across `direction` (rad, from +x towards
    /// +y), darker troughs of relative depth `ripple`; grains of `grain` m with relative
    /// contrast `contrast`; fBm mottling.
    Sand {
        wavelength: f64,
        direction: f64,
        ripple: f64,
        grain: f64,
        contrast: f64,
        seed: u64,
    },
    /// Rock: fBm mottling of feature `size` m, dark cracks of spacing `crack` m and width
    /// `crack_width` m (Worley cell borders), mineral speckle of grain `speckle` m; relative
    /// amplitude `contrast`.
    Rock {
        size: f64,
        crack: f64,
        crack_width: f64,
        speckle: f64,
        contrast: f64,
        seed: u64,
    },
    /// Coral and encrusting growth: patches (colonies) of size `size` m covering a fraction
    /// `cover` of the surface, each in one of `colors` (albedos), with polyps of `polyp` m;
    /// bare substrate (the object's albedo) between them.
    Coral {
        size: f64,
        cover: f64,
        colors: Vec<Rgb>,
        polyp: f64,
        contrast: f64,
        seed: u64,
    },
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Target {
    /// Unique name; target point ids are `"{name}/{index}"` unless the kind defines codes.
    pub name: String,
    pub kind: TargetKind,
    /// `world_from_target`; the target's own frame has its printed face on z = 0, normal +z.
    pub pose: Pose,
    /// Known 3D points (world frame) with ids. Computed by the resolver from `kind` and `pose`.
    pub points: Vec<TargetPoint>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct TargetPoint {
    pub id: String,
    pub world: DVec3,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum TargetKind {
    /// `cols`×`rows` squares of side `square` m; points are the inner corners
    /// ((cols-1)×(rows-1)), row-major from the target's (-x, -y) corner.
    Checkerboard { cols: u32, rows: u32, square: f64 },
    /// Grid of black disks of `diameter` m at `spacing` m on white; points are the disk centres.
    CircleGrid {
        cols: u32,
        rows: u32,
        spacing: f64,
        diameter: f64,
    },
    /// Coded targets (ring-coded disks), `count` of them placed on a grid of `spacing`; ids are
    /// their code numbers.
    Coded {
        count: u32,
        spacing: f64,
        diameter: f64,
        first_code: u32,
    },
    /// Scale bar of `length` m between two disk targets of `diameter` m.
    ScaleBar {
        length: f64,
        width: f64,
        diameter: f64,
    },
    /// Siemens star GSD/resolution target of `diameter` m with `spokes` black sectors; its
    /// point is the centre.
    SiemensStar { diameter: f64, spokes: u32 },
    /// One black disk of `diameter` m on a white plate twice as wide (a GCP or test-field
    /// marker, from a points file); its point is the centre, with the target's name as id.
    Disk { diameter: f64 },
    /// 3D test object: a staircase pyramid of `levels` steps of `step` height and `size` base
    /// width, with a disk target on every corner.
    TestObject {
        size: f64,
        levels: u32,
        step: f64,
        diameter: f64,
    },
}

// ------------------------------------------------------------------------------------------
// Network, diver, render settings
// ------------------------------------------------------------------------------------------

/// One rig position of the network.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RigPose {
    /// Image stem, e.g. `"img_0001"`; each camera's image is `"{camera}_{name}"` when the rig
    /// has more than one camera.
    pub name: String,
    /// `world_from_rig` (the rig frame uses camera axes: x right, y down, z forward).
    pub world_from_rig: Pose,
    /// Time since the start of the survey at which this image is taken, s.
    pub time: f64,
    /// Index of the strip/ring/segment this pose belongs to.
    pub strip: u32,
}

#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct NetworkSummary {
    /// `"explicit"`, `"lawnmower"`, `"spiral"`, `"orbit"`, …
    pub kind: String,
    /// The swim path as a polyline (world), including turns between strips.
    pub path: Vec<DVec3>,
    /// Path length, m.
    pub path_length: f64,
    /// Swim speed used, m/s.
    pub speed: f64,
    /// Survey duration (swim + time triggers), s.
    pub duration: f64,
    /// Nominal camera altitude above the seabed, m (if the network defines one).
    pub altitude: Option<f64>,
    /// Forward overlap and side-lap (fractions) the poses give over a flat seabed, through
    /// the exact port, if the network defines them.
    pub overlap: Option<f64>,
    pub sidelap: Option<f64>,
    /// What the scene asked for (`overlap`, `sidelap`): differs from the above when `strips`
    /// or a distance/time trigger fixes the spacing.
    pub overlap_requested: Option<f64>,
    pub sidelap_requested: Option<f64>,
    /// Distance between exposures along a strip, m, and between strips, m.
    pub spacing: Option<f64>,
    pub strip_spacing: Option<f64>,
    pub strips: u32,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Diver {
    /// Swim speed during the survey, m/s.
    pub speed: f64,
    /// Descent and ascent rates, m/s (positive numbers).
    pub descent_rate: f64,
    pub ascent_rate: f64,
    /// Surface air consumption, m³/s of surface-equivalent gas (input as l/min).
    pub sac: f64,
    pub cylinders: Vec<Cylinder>,
    /// Bühlmann gradient factors, fractions (e.g. 0.3, 0.7 → GF 30/70).
    pub gf_low: f64,
    pub gf_high: f64,
    /// Gas that must remain in every cylinder at the surface, Pa (e.g. 50 bar).
    pub reserve: f64,
    /// Water is salt (density 1030 kg/m³, Subsurface's default) or fresh (1000).
    pub salt_water: bool,
    /// Highest pO₂ allowed for bottom and stage gases, and for deco gases, bar (Subsurface:
    /// 1.4 / 1.6).
    #[serde(default = "po2_bottom_default")]
    pub po2_bottom: f64,
    #[serde(default = "po2_deco_default")]
    pub po2_deco: f64,
    /// Deepest equivalent narcotic depth a gas named by the planner may have, m (O₂ counted as
    /// narcotic; default [`DEFAULT_END_LIMIT`]).
    #[serde(default = "end_limit_default")]
    pub end_limit: f64,
    /// Whether decompression is planned (`diver.deco = "planned"`) or the dive must stay
    /// within the NDL (`"none"`, the default).
    #[serde(default, skip_serializing_if = "deco_mode_is_none")]
    pub deco: DecoMode,
}

fn po2_bottom_default() -> f64 {
    1.4
}
fn po2_deco_default() -> f64 {
    1.6
}
fn end_limit_default() -> f64 {
    DEFAULT_END_LIMIT
}

/// The END limit without `diver.end_limit`, m: 30 m, the customary narcosis limit of
/// technical-diving agencies (GUE, TDI, IANTD).
pub const DEFAULT_END_LIMIT: f64 = 30.0;

/// `diver.deco`: whether the dive may need decompression stops.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum DecoMode {
    /// A no-decompression dive: a dive that needs stops is NOT SAFE AS PLANNED.
    #[default]
    None,
    /// Decompression is planned and accepted: a dive whose whole plan holds (stops on the
    /// gases carried, every gas where it is breathed, the gas rules, CNS and pO₂, the
    /// lost-gas plans) is "OK, decompression planned".
    Planned,
}

fn deco_mode_is_none(m: &DecoMode) -> bool {
    *m == DecoMode::None
}

/// What a cylinder is breathed for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum CylinderRole {
    /// Back gas: breathed from the surface, on the bottom and on the ascent.
    #[default]
    Bottom,
    /// Carried bottom gas, breathed before the back gas down to its reserve.
    Stage,
    /// Travel gas: breathed on the descent from the surface down to its switch depth (where
    /// the bottom gas takes over), and on the ascent from its switch depth up. It carries a
    /// bottom gas that is hypoxic at the surface, or too narcotic or too rich in O₂ for the
    /// shallow part, to where it is breathable.
    Travel,
    /// Breathed only on the ascent, from its switch depth up.
    Deco,
    /// Not breathed in the plan: carried for the loss of the bottom gas. Its plan is the
    /// ascent from the end of the bottom time on it (and the travel and deco gases from their
    /// switch depths), checked like the plan itself.
    Bailout,
}

impl CylinderRole {
    /// The role as the scene writes it.
    pub fn name(self) -> &'static str {
        match self {
            CylinderRole::Bottom => "bottom",
            CylinderRole::Stage => "stage",
            CylinderRole::Travel => "travel",
            CylinderRole::Deco => "deco",
            CylinderRole::Bailout => "bailout",
        }
    }
    /// Back gas or stage: breathed on the bottom, pooled for the gas rules.
    pub fn is_bottom(self) -> bool {
        matches!(self, CylinderRole::Bottom | CylinderRole::Stage)
    }
    /// Has a switch depth: travel and deco gases.
    pub fn switched(self) -> bool {
        matches!(self, CylinderRole::Travel | CylinderRole::Deco)
    }
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Cylinder {
    pub name: String,
    /// Water volume, m³.
    pub volume: f64,
    /// Fill pressure, Pa.
    pub pressure: f64,
    /// O₂ and He fractions (the rest is N₂).
    pub o2: f64,
    pub he: f64,
    #[serde(default)]
    pub role: CylinderRole,
    /// Travel or deco gas: depth (m) to which a travel gas is breathed on the descent and from
    /// which a travel or deco gas is breathed on the ascent; `None` = the planner's default
    /// (a deco gas: its MOD at the diver's deco pO₂; a travel gas: the deepest depth within
    /// its bottom pO₂ and the END limit), rounded down to whole metres.
    #[serde(default)]
    pub switch_depth: Option<f64>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RenderSettings {
    /// Samples per pixel.
    pub samples: u32,
    /// Seed for every random choice of every backend.
    pub seed: u64,
    /// Maximum path length (bounces).
    pub max_bounces: u32,
    /// Render one pass per channel with that channel's indices.
    pub dispersion: bool,
    /// Outputs requested: `"rgb"`, `"depth"`, `"truth"`.
    pub outputs: Vec<String>,
    /// Exposure multiplier applied to the PNG preview only (EXR stays linear).
    pub exposure: f64,
    /// The native renderer's optional illumination denoiser (`None`: off): the Gaussian
    /// radius in pixels (`poser::backend::native::denoise`).
    pub denoise_radius: Option<f64>,
    /// The native renderer's noise target (`None`: `samples` per pixel everywhere)
    /// (`poser::backend::native::adaptive`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise: Option<NoiseTarget>,
    /// How the native renderer carries daylight through the water (`render.daylight`).
    #[serde(default)]
    pub daylight: Daylight,
    /// How the native renderer reads textures at the camera ray's first hit
    /// (`render.texture_filter`).
    #[serde(default, skip_serializing_if = "TextureFilter::is_footprint")]
    pub texture_filter: TextureFilter,
    /// How the native renderer treats the sea surface seen from below
    /// (`render.surface_from_below`).
    #[serde(default, skip_serializing_if = "Underside::is_fresnel")]
    pub surface_from_below: Underside,
    /// The native renderer's numbers for a pixel's samples (`render.sampler`).
    #[serde(default, skip_serializing_if = "SamplerKind::is_sobol")]
    pub sampler: SamplerKind,
    /// Render only this rectangle of every image (`poser render --crop`; `None`: the whole
    /// image).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub crop: Option<Crop>,
}

/// A rectangle of an image rendered alone (`poser render --crop X,Y,W,H`), in pixels of the
/// image as rendered: `x` to the right and `y` down from the top-left corner. Every backend
/// samples the rectangle's pixels as it samples them in the whole image (the native renderer
/// with the very same random numbers), and writes an image of `width` × `height`: its pixel
/// (i, j) is the whole image's pixel (x + i, y + j). The ground truth stays in the whole
/// image's pixel coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Crop {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

impl Crop {
    /// Whether the rectangle is non-empty and lies inside a `width` × `height` image.
    pub fn fits(&self, width: u32, height: u32) -> bool {
        self.width >= 1
            && self.height >= 1
            && self.x as u64 + self.width as u64 <= width as u64
            && self.y as u64 + self.height as u64 <= height as u64
    }

    /// The rectangle of `cam`'s image that is rendered: `(x, y, width, height)`, the whole
    /// image without a crop.
    pub fn region(crop: Option<Crop>, cam: &Camera) -> (u32, u32, u32, u32) {
        match crop {
            Some(c) => (c.x, c.y, c.width, c.height),
            None => (0, 0, cam.width, cam.height),
        }
    }
}

/// `render.sampler`: how the native renderer draws the random numbers of a pixel's samples
/// (`poser::backend::native::sampler`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SamplerKind {
    /// The default: an Owen-scrambled Sobol sequence over the pixel's samples in each
    /// sample's first draws.
    #[default]
    Sobol,
    /// Every draw independent.
    Independent,
}

impl SamplerKind {
    pub fn is_sobol(&self) -> bool {
        *self == SamplerKind::Sobol
    }
}

/// `render.surface_from_below`: the sea surface as the light coming up to it meets it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Underside {
    /// The default: a flat or wavy sea surface reflects the light coming up to it (unpolarised
    /// Fresnel, totally beyond the critical angle), and the sky is seen through Snell's window
    /// (`docs/column.md`, "The sea surface seen from below").
    #[default]
    Fresnel,
    /// The light coming up leaves, and the sky is an isotropic radiance below the surface, as
    /// Mitsuba and Cycles have it.
    Open,
}

impl Underside {
    pub fn is_fresnel(&self) -> bool {
        *self == Underside::Fresnel
    }
}

/// `render.texture_filter`: the native renderer's texture lookup at the camera ray's first hit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TextureFilter {
    /// The default: the texture averaged over the pixel's footprint on the surface (mip
    /// levels, `poser::texture::mip`).
    #[default]
    Footprint,
    /// One bilinear lookup at the hit per sample (the samples average the pixel).
    Point,
}

impl TextureFilter {
    pub fn is_footprint(&self) -> bool {
        *self == TextureFilter::Footprint
    }
}

/// `render.daylight`: the native renderer's estimator for daylight in the water.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Daylight {
    /// The default: the column where it applies ([`Model::column_input`]) and every view ends
    /// on the scene's seabed ([`Model::daylight_choice`]), else traced.
    #[default]
    Auto,
    /// Light the scene with the solved water column ([`poser_optics::column`]).
    Column,
    /// Random walks through the water, as Mitsuba and Cycles do.
    Traced,
}

/// `render.noise`: adaptive sampling to a relative standard error per pixel.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NoiseTarget {
    /// Relative standard error of each pixel's mean aimed at; with `against_sensor`, the ratio
    /// of the render's noise to the sensor's (1: `noise = "sensor"`).
    pub relative: f64,
    /// The most samples a pixel takes after its pilot (`None`: 16 × the pilot's samples).
    pub max_samples: Option<u32>,
    /// `noise = "sensor"`: aim at the sensor's own noise at each pixel, at the exposure the
    /// sensor stage chooses for the pilot image (needs a `[sensor]` or `--sensor`).
    #[serde(default)]
    pub against_sensor: bool,
}

impl NoiseTarget {
    /// The most samples after a pilot of `pilot` samples.
    pub fn max_samples_for(&self, pilot: u32) -> u32 {
        self.max_samples.unwrap_or(16 * pilot).max(pilot)
    }
}

/// What the scene needs modelled, decided once, with reasons a person can read.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Needs {
    /// A participating medium (σt > 0 somewhere).
    pub medium: bool,
    /// The medium is confined to a box around each camera.
    pub medium_box: bool,
    /// Refraction at a housing port.
    pub refraction: bool,
    /// One render pass per channel (dispersion asked for *and* its effect ≥ 0.1 px).
    pub per_channel_passes: bool,
    /// The sun must be refracted through the sea surface.
    pub sun_refraction: bool,
    /// Caustics from a wavy surface.
    pub caustics: bool,
    /// Lateral colour at the image corner (max over cameras), px, between R and B.
    pub lateral_color_px: f64,
    /// One line per decision, for `poser explain`.
    pub reasons: Vec<String>,
}

impl Model {
    /// Checks what every back end relies on (finite numbers, rotations, positive sizes, …;
    /// [`valid`]), naming each offending value by its path in the model.
    pub fn validate(&self) -> Result<(), valid::Invalid> {
        valid::validate(self)
    }

    /// The air–water interface for channel `ch` (0 = R, 1 = G, 2 = B) that a camera above the
    /// water looks through: the flat surface, or the waves (the same seeded field as the
    /// native renderer's caustics). `None` without water or without a modelled surface.
    pub fn sea_interface(&self, ch: usize) -> Option<poser_optics::surface::SeaInterface> {
        use poser_optics::surface::SeaInterface;
        use poser_optics::waves::{WIND_DIRECTION, WaveField};
        let n_water = self.water.as_ref()?.ior[ch.min(2)];
        match self.site.surface {
            SeaSurface::None => None,
            SeaSurface::Flat => Some(SeaInterface::flat(n_water)),
            SeaSurface::Waves {
                height,
                wavelength,
                wind_speed,
            } => Some(SeaInterface {
                field: WaveField::new(
                    height,
                    wavelength,
                    wind_speed,
                    WIND_DIRECTION,
                    self.site.seed,
                ),
                n_water,
            }),
        }
    }

    /// Whether camera `cam` at rig pose `pose` is in the air above every crest, looking down
    /// through the sea surface (a drone).
    pub fn above_surface(&self, pose: usize, cam: usize) -> bool {
        self.sea_interface(1)
            .is_some_and(|s| s.above(self.world_from_camera(pose, cam).translation))
    }

    /// Whether any image of the network is taken from above the sea surface.
    pub fn any_above_surface(&self) -> bool {
        (0..self.poses.len()).any(|p| (0..self.cameras.len()).any(|c| self.above_surface(p, c)))
    }

    /// Index of the medium the cameras' ports open into, per channel (1 in air).
    pub fn ambient_ior(&self) -> Rgb {
        self.water.as_ref().map(|w| w.ior).unwrap_or([1.0; 3])
    }

    /// `world_from_camera` for camera `cam` at rig pose `pose`.
    pub fn world_from_camera(&self, pose: usize, cam: usize) -> Pose {
        self.poses[pose]
            .world_from_rig
            .compose(&self.cameras[cam].rig_from_camera)
    }

    /// Name of the image taken by camera `cam` at rig pose `pose`.
    pub fn image_name(&self, pose: usize, cam: usize) -> String {
        if self.cameras.len() == 1 {
            self.poses[pose].name.clone()
        } else {
            format!("{}_{}", self.cameras[cam].name, self.poses[pose].name)
        }
    }

    /// [`Model::with_resolution_scale`] with the factor checked: in (0, 4].
    pub fn with_checked_resolution_scale(self, scale: f64) -> Result<Model, String> {
        if scale.is_finite() && scale > 0.0 && scale <= 4.0 {
            Ok(self.with_resolution_scale(scale))
        } else {
            Err(format!(
                "scale {scale}: expected a factor in (0, 4], e.g. 0.25 for a quarter-resolution preview"
            ))
        }
    }

    /// The index of the rig's camera called `name`; the error lists the names there are.
    pub fn camera_index(&self, name: &str) -> Result<usize, String> {
        self.cameras
            .iter()
            .position(|c| c.name == name)
            .ok_or_else(|| {
                let names: Vec<&str> = self.cameras.iter().map(|c| c.name.as_str()).collect();
                format!(
                    "camera `{name}`: no such camera (the rig has: {})",
                    names.join(", ")
                )
            })
    }

    /// Every camera resampled by `scale` ([`Camera::with_resolution_scale`]).
    pub fn with_resolution_scale(mut self, scale: f64) -> Model {
        for c in &mut self.cameras {
            *c = c.with_resolution_scale(scale);
        }
        self
    }

    /// The most port interfaces any camera's rays cross ([`Port::interfaces`]).
    pub fn port_interfaces(&self) -> u32 {
        self.cameras
            .iter()
            .map(|c| c.port.interfaces())
            .max()
            .unwrap_or(0)
    }
}

/// The exact projection of a camera of the model: the optics core's [`Projector`] placed at
/// every rig pose of the network (the optics itself knows nothing of the model).
impl Model {
    /// The projector of camera `cam` for `channel` (0 = R, 1 = G, 2 = B).
    pub fn projector(&self, cam: usize, channel: usize) -> Result<Projector, String> {
        let camera = self.cameras.get(cam).ok_or_else(|| {
            format!(
                "camera index {cam} out of range ({} cameras)",
                self.cameras.len()
            )
        })?;
        if channel > 2 {
            return Err(format!(
                "channel {channel} out of range (0 = R, 1 = G, 2 = B)"
            ));
        }
        let p = Projector::for_camera(camera, channel, self.ambient_ior()[channel])?;
        Ok(p.with_poses(
            (0..self.poses.len())
                .map(|i| self.world_from_camera(i, cam))
                .collect(),
        ))
    }
}

// ------------------------------------------------------------------------------------------
// Sensor (the camera after the lens; applied by `poser::sensor`)
// ------------------------------------------------------------------------------------------

/// A camera sensor and its image pipeline (see `docs/sensor.md`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Sensor {
    /// Full-well capacity, e⁻.
    pub full_well: f64,
    /// Read noise, e⁻ RMS.
    pub read_noise: f64,
    /// Quantum efficiency per channel (e⁻ per photon).
    pub quantum_efficiency: Rgb,
    /// ADC bits (8..=16).
    pub bits: u32,
    /// Black level, DN.
    pub black_level: u32,
    /// ISO speed and the ISO at which the full well fills the ADC.
    pub iso: f64,
    pub base_iso: f64,
    pub exposure: SensorExposure,
    /// Exposure time, s (manual exposure; fallback of auto exposure).
    pub shutter: f64,
    /// Aperture f-number used for the exposure.
    pub f_number: f64,
    /// Lens and port transmittance to the sensor.
    pub transmittance: f64,
    pub white_balance: WhiteBalance,
    pub tone: ToneCurve,
    pub format: SensorFormat,
    /// Shot and read noise on.
    pub noise: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "mode")]
pub enum SensorExposure {
    /// `shutter` as given.
    Manual,
    /// Shutter chosen so that the metered value lands at `target` × full scale.
    Auto {
        meter: Meter,
        percentile: f64,
        target: f64,
    },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Meter {
    /// A percentile of the brightest white-balanced channel per pixel.
    Highlights,
    /// The mean luminance (Rec. 709 weights) of the white-balanced image.
    Average,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "mode", content = "gains")]
pub enum WhiteBalance {
    None,
    GreyWorld,
    Fixed(Rgb),
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "curve", content = "gamma")]
pub enum ToneCurve {
    Linear,
    Srgb,
    Gamma(f64),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "format", content = "quality")]
pub enum SensorFormat {
    Jpeg(u8),
    Png,
}

impl Default for Sensor {
    /// A typical 1/1.8" machine-vision/compact sensor at base ISO with auto exposure.
    fn default() -> Sensor {
        Sensor {
            full_well: 15000.0,
            read_noise: 3.0,
            quantum_efficiency: [0.45, 0.55, 0.45],
            bits: 12,
            black_level: 64,
            iso: 100.0,
            base_iso: 100.0,
            exposure: SensorExposure::Auto {
                meter: Meter::Highlights,
                percentile: 0.99,
                target: 0.85,
            },
            shutter: 0.008,
            f_number: 8.0,
            transmittance: 0.9,
            white_balance: WhiteBalance::GreyWorld,
            tone: ToneCurve::Srgb,
            format: SensorFormat::Jpeg(95),
            noise: true,
        }
    }
}

/// Name of the single camera when the scene gives it none (`[camera]` without `name`).
pub const DEFAULT_CAMERA_NAME: &str = "cam";

/// Whether a name may become part of a file name (camera names form image names in a rig):
/// letters and digits (any script), `_`, `-`, `.`; not empty, not starting with `.`, at most
/// 100 characters. So no separator, no `..`, no control or XML-illegal character. The front
/// end checks every such name with this rule (`scene::resolve`, error E0234).
pub fn is_safe_file_name(s: &str) -> bool {
    !s.is_empty()
        && s.chars().count() <= 100
        && !s.starts_with('.')
        && s.chars()
            .all(|c| c.is_alphanumeric() || matches!(c, '_' | '-' | '.'))
}

// ------------------------------------------------------------------------------------------
// The water column's light
// ------------------------------------------------------------------------------------------

/// Photons per channel of the column solve ([`poser_optics::column`]).
pub const COLUMN_PHOTONS: usize = 400_000;
/// Photons per channel of the quick column solve that measures what a bounce limit cuts off
/// ([`Model::bounce_cut`]): shares to a few tenths of a point, in tens of milliseconds.
pub const BOUNCE_PHOTONS: usize = 64_000;
/// The share of the cameras' daylight a bounce limit may cut off before `validate` warns
/// (W0239).
pub const BOUNCE_CUT_WARN: f64 = 0.01;

/// What a bounce limit cuts off of traced daylight ([`Model::bounce_cut`]).
#[derive(Debug, Clone)]
pub struct BounceCut {
    /// `render.bounces`.
    pub bounces: u32,
    /// Per channel, the share of the light the cameras see that the limit cuts off (0 in
    /// channels that are black at the seabed).
    pub share: [f64; 3],
    /// Per channel, whether it keeps enough light at the seabed to be seen (else its share is
    /// not counted).
    pub visible: [bool; 3],
    /// The smallest limit cutting off at most [`BOUNCE_CUT_WARN`] (`None`: more than 254).
    pub needed: Option<u32>,
}

impl BounceCut {
    /// The largest share over the channels.
    pub fn worst(&self) -> f64 {
        self.share.iter().copied().fold(0.0, f64::max)
    }

    /// `"0.7 % / 6.7 % / 23.3 %"` (`"black"` for a channel without light at the seabed).
    pub fn shares_text(&self) -> String {
        [0, 1, 2]
            .map(|c| {
                if self.visible[c] {
                    format!("{:.1} %", self.share[c] * 100.0)
                } else {
                    "black".to_string()
                }
            })
            .join(" / ")
    }

    /// `"27"`, or `"more than 254"`.
    pub fn needed_text(&self) -> String {
        self.needed
            .map_or("more than 254".to_string(), |n| n.to_string())
    }
}

impl Model {
    /// The plane-parallel water column the scene's daylight comes through, or why the scene is
    /// not one: water everywhere below a flat or wavy surface, scattering and absorbing in
    /// every channel, lit by the sun or the sky, over a seabed at `site.depth`. The bottom's
    /// albedo is the largest horizontal plane or seabed's (else the mean of the objects').
    pub fn column_input(&self) -> Result<poser_optics::column::ColumnInput, String> {
        let input = self.column_physics()?;
        let above = (0..self.poses.len())
            .flat_map(|p| (0..self.cameras.len()).map(move |c| (p, c)))
            .any(|(p, c)| self.world_from_camera(p, c).translation.z >= 0.0);
        if above {
            return Err("a camera is above the water".into());
        }
        Ok(input)
    }

    /// The sea surface as the light from below meets it in the native renderer: reflecting
    /// (Fresnel, the water's index per channel) where the scene has water under a flat or wavy
    /// surface and `render.surface_from_below = "fresnel"`, else open.
    pub fn underside(&self) -> poser_optics::column::Top {
        use poser_optics::column::Top;
        match &self.water {
            Some(w)
                if self.render.surface_from_below == Underside::Fresnel
                    && !matches!(self.site.surface, SeaSurface::None)
                    && !matches!(w.extent, WaterExtent::BoxAroundCamera { .. }) =>
            {
                Top::Fresnel(w.ior)
            }
            _ => Top::Open,
        }
    }

    /// The one line a backend whose sea surface is open from below (Mitsuba, Cycles) warns
    /// with where the native renderer's reflects ([`Model::underside`]) and daylight comes
    /// down: the light that surface returns, and the sky's Snell's window, are left out.
    pub fn open_underside_warning(&self, backend: &str) -> Option<String> {
        let daylight = self.sun.is_some()
            || self
                .lights
                .iter()
                .any(|l| matches!(l.kind, LightKind::Ambient { .. }));
        (daylight && self.underside() != poser_optics::column::Top::Open).then(|| {
            format!(
                "{backend} has the sea surface open from below: no Snell's window and no \
                 reflection of the light coming up, which the native renderer models (a \
                 sky-lit seabed 35 m down gets about a quarter more light); `poser explain` \
                 prints the difference at this scene's seabed, and `--set \
                 render.surface_from_below='\"open\"'` compares like for like (docs/column.md)"
            )
        })
    }

    /// The sun's propagation direction in the water per channel (R, G, B): refracted at the
    /// flat surface with each channel's water index, so that blue, bent more, runs a little
    /// steeper than red. G's is [`Sun::direction_water`] itself, and the others follow from it
    /// by Snell's law, `n_c sin θ_c = n_G sin θ_G` in the same azimuth (for a resolved scene
    /// that is `sin θ_air`). Without water or without a sea surface all three are
    /// `direction_water`. `None` without a sun.
    pub fn sun_directions_water(&self) -> Option<[DVec3; 3]> {
        let s = self.sun.as_ref()?;
        let g = s.direction_water;
        Some(match &self.water {
            Some(w) if !matches!(self.site.surface, SeaSurface::None) && g.z < 0.0 => {
                let (horizontal, len) = (DVec3::new(g.x, g.y, 0.0), g.length());
                let sin_g = horizontal.length() / len;
                [0, 1, 2].map(|c| {
                    let sin_c = sin_g * w.ior[1] / w.ior[c];
                    match horizontal.try_normalize() {
                        Some(h) if c != 1 && sin_c < 1.0 => {
                            (h * sin_c - DVec3::Z * (1.0 - sin_c * sin_c).sqrt()) * len
                        }
                        _ => g,
                    }
                })
            }
            _ => [g; 3],
        })
    }

    /// The plane-parallel column of the scene's water and daylight, wherever its cameras are
    /// ([`Model::column_input`] without the cameras' check).
    pub fn column_physics(&self) -> Result<poser_optics::column::ColumnInput, String> {
        use poser_optics::column::{ColumnInput, ColumnSun};
        let w = self.water.as_ref().ok_or("the scene has no water")?;
        if let WaterExtent::BoxAroundCamera { .. } = w.extent {
            return Err(
                "the water is a box around the camera, not a column from the surface down".into(),
            );
        }
        if let Some(c) = (0..3).find(|&c| !(w.absorption[c] > 0.0)) {
            return Err(format!(
                "the water does not absorb in channel {} (σa = 0): the column's light would \
                 never converge",
                ["R", "G", "B"][c]
            ));
        }
        let sun = self
            .sun
            .as_ref()
            .zip(self.sun_directions_water())
            .filter(|(_, dirs)| dirs.iter().all(|d| d.z < 0.0))
            .map(|(s, dirs)| ColumnSun {
                dirs: dirs.map(DVec3::normalize),
                irradiance: s.irradiance_water,
            });
        let mut ambient = [0.0; 3];
        for l in &self.lights {
            if let LightKind::Ambient { radiance } = l.kind {
                for c in 0..3 {
                    ambient[c] += radiance[c];
                }
            }
        }
        if sun.is_none() && ambient.iter().all(|a| *a <= 0.0) {
            return Err("no daylight (sun or ambient sky) comes down the water".into());
        }
        if !(self.site.depth > 0.0) {
            return Err(format!(
                "the site's depth is {} m: the column needs a seabed below the surface",
                self.site.depth
            ));
        }
        Ok(ColumnInput {
            depth: self.site.depth,
            sigma_a: w.absorption,
            sigma_s: w.scattering,
            phase: w.phase.phase_fn(),
            sun,
            ambient,
            bottom_albedo: self.bottom_albedo(),
            top: self.underside(),
            photons: COLUMN_PHOTONS,
            seed: self.render.seed,
        })
    }

    /// What `render.bounces` cuts off of traced daylight, measured on the scene's water column
    /// solved quickly ([`BOUNCE_PHOTONS`], one round): per channel, the worst share over the
    /// cameras' depths of the light seen looking down
    /// ([`poser_optics::column::Column::share_seen_beyond`]), and the bounces that would cut
    /// off at most [`BOUNCE_CUT_WARN`]. `None` where the scene is not a column
    /// ([`Model::column_physics`]) or the column cannot be solved.
    pub fn bounce_cut(&self) -> Option<BounceCut> {
        let mut input = self.column_physics().ok()?;
        input.photons = BOUNCE_PHOTONS;
        let col = quick_column(&input, 1)?;
        let mut depths: Vec<f64> = (0..self.poses.len())
            .flat_map(|p| (0..self.cameras.len()).map(move |c| (p, c)))
            .map(|(p, c)| {
                let z = -self.world_from_camera(p, c).translation.z;
                // one depth per layer of the table
                let dz = col.depth / poser_optics::column::NZ as f64;
                ((z.clamp(0.0, col.depth) / dz).floor() + 0.5) * dz
            })
            .collect();
        depths.sort_by(f64::total_cmp);
        depths.dedup();
        let b = self.render.max_bounces;
        let mut share = [0.0; 3];
        for &z in &depths {
            let s = col.share_seen_beyond(z, b);
            for c in 0..3 {
                if col.visible_at_bottom(c) {
                    share[c] = f64::max(share[c], s[c]);
                }
            }
        }
        Some(BounceCut {
            bounces: b,
            share,
            visible: [0, 1, 2].map(|c| col.visible_at_bottom(c)),
            needed: col.bounces_for(&depths, BOUNCE_CUT_WARN),
        })
    }

    /// The reflecting sea surface against the open one: per channel, how much more daylight
    /// reaches the seabed when the flat surface reflects the light coming up from below
    /// (Fresnel, totally beyond the critical angle) and the sky comes in through Snell's
    /// window, as a share of E_d there under the open surface (Mitsuba's and Cycles' model;
    /// the native renderer's is [`Model::underside`]). `explain` prints it (docs/column.md).
    /// `None` where the scene is not a column.
    /// A channel black at the seabed ([`poser_optics::column::Column::visible_at_bottom`]) is
    /// `None`.
    pub fn surface_reflection_gain(&self) -> Option<[Option<f64>; 3]> {
        use poser_optics::column::Top;
        let mut open = self.column_physics().ok()?;
        open.photons = BOUNCE_PHOTONS;
        open.top = Top::Open;
        let n = self.water.as_ref()?.ior;
        let fresnel = poser_optics::column::ColumnInput {
            top: Top::Fresnel(n),
            ..open.clone()
        };
        let a = quick_column(&open, 4)?;
        let b = quick_column(&fresnel, 4)?;
        let nz = poser_optics::column::NZ;
        // Both solves draw the same photons until the first reflection at the surface, so
        // their difference is far less noisy than either (±0.5 points measured).
        Some([0, 1, 2].map(|c| {
            let (ea, eb) = (a.profiles[c].e_d(nz), b.profiles[c].e_d(nz));
            (a.visible_at_bottom(c) && ea > 0.0).then(|| eb / ea - 1.0)
        }))
    }

    /// The albedo of the column's bottom: the largest horizontal plane or seabed object's,
    /// else the mean over the objects, else 0.
    pub fn bottom_albedo(&self) -> Rgb {
        let mut best: Option<(f64, Rgb)> = None;
        for o in &self.objects {
            let area = match o.shape {
                Shape::Plane { width, height } => width * height * o.scale.x * o.scale.y,
                Shape::Seabed { width, length, .. } => width * length * o.scale.x * o.scale.y,
                _ => continue,
            };
            let up = o.pose.rotation * DVec3::Z;
            if up.z.abs() < 0.9 {
                continue;
            }
            if best.is_none_or(|(a, _)| area > a) {
                best = Some((area, o.material.albedo));
            }
        }
        if let Some((_, a)) = best {
            return a;
        }
        if self.objects.is_empty() {
            return [0.0; 3];
        }
        let n = self.objects.len() as f64;
        [0, 1, 2].map(|c| {
            self.objects
                .iter()
                .map(|o| o.material.albedo[c])
                .sum::<f64>()
                / n
        })
    }

    /// The column the native renderer lights this scene with (`None`: daylight is traced), and
    /// why. `past_seabed` is the share of the cameras' view that heads down and hits nothing
    /// (`poser::geometry::seen`; `None`: not measured, taken as none): under `"auto"` any such
    /// view keeps daylight traced, because the column lights that water as if the seabed went on
    /// while Mitsuba, Cycles and traced daylight leave it bottomless (docs/column.md, "Views past
    /// the seabed").
    pub fn daylight_choice(
        &self,
        past_seabed: Option<f64>,
    ) -> (Option<poser_optics::column::ColumnInput>, String) {
        if self.render.daylight == Daylight::Traced {
            return (
                None,
                "traced (render.daylight = \"traced\"): random walks through the water".into(),
            );
        }
        let glass = self.objects.iter().find(|o| o.material.glass.is_some());
        match self.column_input() {
            Ok(_) if self.render.daylight == Daylight::Auto && glass.is_some() => (
                None,
                format!(
                    "traced: glass object `{}` refracts the daylight, which the column's light \
                     (next-event estimated with shadow rays) would miss behind it",
                    glass.map_or("", |o| o.name.as_str())
                ),
            ),
            Ok(_)
                if self.render.daylight == Daylight::Auto
                    && past_seabed.is_some_and(|p| p > 0.0) =>
            {
                (
                    None,
                    format!(
                        "traced: {:.1} % of the cameras' view looks past the seabed into water \
                         without a bottom, which the column would light as if the seabed went on \
                         (help: widen the seabed past the network's footprint, or set \
                         render.daylight = \"column\" to light it so)",
                        100.0 * past_seabed.unwrap_or(0.0)
                    ),
                )
            }
            Ok(input) => (
                Some(input),
                format!(
                    "column{}: daylight from the plane-parallel water column solved once \
                     (docs/column.md); the scene traces only its own geometry, strobes and the \
                     sun's first scattering",
                    if self.render.daylight == Daylight::Column {
                        " (render.daylight = \"column\")"
                    } else {
                        " (render.daylight = \"auto\", the default)"
                    }
                ),
            ),
            Err(why) => (None, format!("traced: the column does not apply ({why})")),
        }
    }
}

/// A quick column solve ([`poser_optics::column::solve_rounds`]), remembered for the life of
/// the process: resolution measures the bounce limit of every scene lit through a column
/// ([`Model::bounce_cut`]), and a process that loads one site many times (a test binary, the
/// Python module, a lesson's variants, the dive planner's alternatives) then solves its column
/// once. The key is the whole input, seed and photon count included (`Debug` prints every
/// `f64` exactly), so a hit is the very column a solve would return: no result depends on the
/// cache. The few most recent columns are kept.
fn quick_column(
    input: &poser_optics::column::ColumnInput,
    rounds: usize,
) -> Option<std::sync::Arc<poser_optics::column::Column>> {
    use poser_optics::column::Column;
    use std::sync::{Arc, Mutex};
    static CACHE: Mutex<Vec<(String, Arc<Column>)>> = Mutex::new(Vec::new());
    const KEEP: usize = 8;
    let key = format!("{rounds} {input:?}");
    let find = |c: &[(String, Arc<Column>)]| c.iter().find(|e| e.0 == key).map(|e| e.1.clone());
    if let Some(col) = find(&CACHE.lock().unwrap_or_else(|p| p.into_inner())) {
        return Some(col);
    }
    let col = Arc::new(poser_optics::column::solve_rounds(input, rounds).ok()?);
    let mut cache = CACHE.lock().unwrap_or_else(|p| p.into_inner());
    if find(&cache).is_none() {
        if cache.len() == KEEP {
            cache.remove(0);
        }
        cache.push((key, col.clone()));
    }
    Some(col)
}

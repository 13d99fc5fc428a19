//! The `[[objects]]` of a scene: their shape (glTF mesh, plane, box, sphere, cylinder,
//! generated seabed, boulders, coral), placement, scale and material (albedo and texture
//! pattern). Mesh paths are resolved relative to the scene file that names them, checked to be
//! readable glTF, OBJ or PLY and kept inside the scene's folder; their georeference keys are
//! [`super::georef`]'s.

use super::{Spans, placement};
use crate::model::*;
use crate::scene::check;
use crate::scene::diag::{Diagnostic, Span};
use crate::scene::format::types as F;
use crate::scene::reader::{Cx, Tab};
use crate::scene::source::{Sources, Val};
use crate::units::Dim;
use glam::DVec3;
use std::path::Path;

/// Every `[[objects]]` entry; generated objects without a `seed` get `site.seed` + their index.
pub(super) fn objects(
    cx: &mut Cx,
    t: &mut Tab,
    site: &Site,
    sources: &Sources,
    scene: &Path,
    spans: &mut Spans,
) -> Vec<Object> {
    let mut out = Vec::new();
    for (i, n) in t.tables(cx, F::Scene::objects).into_iter().enumerate() {
        let path = format!("objects[{i}]");
        let mut o = Tab::open(cx, Some(n), &path, n.span);
        let name = o
            .opt_str(cx, F::Object::name)
            .unwrap_or_else(|| format!("object{i}"));
        let shape_kind = o
            .choice(
                cx,
                F::Object::shape,
                &[
                    "mesh", "plane", "box", "sphere", "cylinder", "seabed", "boulders", "coral",
                ],
            )
            .unwrap_or("box");
        let seed = o
            .opt_u64(cx, F::Object::seed)
            .unwrap_or(site.seed.wrapping_add(i as u64));
        let errors = cx.diags.iter().filter(|d| d.is_error()).count();
        let shape = shape(cx, &mut o, shape_kind, seed, sources, scene);
        let mesh_ok = cx.diags.iter().filter(|d| d.is_error()).count() == errors;
        let backdrop = o.bool(cx, F::Object::backdrop, false);
        let default_pos = if matches!(shape, Shape::Seabed { .. } | Shape::Boulders { .. }) {
            DVec3::new(0.0, 0.0, -site.depth)
        } else {
            DVec3::ZERO
        };
        let pose = placement(cx, &mut o, default_pos);
        let scale = match o.get(F::Object::scale) {
            Some(n) if matches!(n.val, Val::Array(_)) => {
                crate::scene::reader::vector(cx, n, Dim::Number, &o.full(F::Object::scale), Some(3))
                    .map(|v| DVec3::new(v[0], v[1], v[2]))
            }
            Some(n) => crate::scene::reader::number(cx, n, Dim::Number, &o.full(F::Object::scale))
                .map(DVec3::splat),
            None => None,
        }
        .unwrap_or(DVec3::ONE);
        if !(scale.min_element() > 0.0) {
            let sp = o.span_of(F::Object::scale);
            cx.push(
                Diagnostic::error("E0283", "the scale must be positive")
                    .label(sp, "every factor must be > 0")
                    .help("use `scale = 1` for the original size"),
            );
        }
        if let Shape::Mesh {
            path,
            up_axis,
            offset: _,
            ..
        } = &shape
            && mesh_ok
            && !o.has(F::Object::offset)
            && !o.has(F::Object::offset_file)
        {
            super::georef::warn_far(
                cx,
                Path::new(path),
                *up_axis,
                scale,
                o.span_of(F::Object::path),
            );
        }
        let mut shape = shape;
        if let Shape::Seabed { relief, .. } = &mut shape
            && o.has(F::Object::relief_file)
        {
            *relief = relief_points(cx, &mut o, &pose, scale, sources, scene);
        }
        let mut material = material(cx, &mut o, 0.3);
        material.glass = glass(cx, &mut o, shape_kind, scale);
        if let Some(w) = fill(cx, &mut o, shape_kind, scale, site) {
            material.glass = Some(crate::model::Glass {
                name: "fill".into(),
                ior: w.ior,
            });
            material.fill = Some(w);
        }
        spans.objects.push(o.span);
        o.finish_as(cx, Some(&format!("a {shape_kind} object (`{path}`)")));
        out.push(Object {
            name,
            shape,
            pose,
            scale,
            material,
            backdrop,
        });
    }
    out
}

/// The shape of an object by its `shape` key; the generated ones (seabed, boulders, coral) are
/// made from `seed`.
fn shape(
    cx: &mut Cx,
    o: &mut Tab,
    kind: &str,
    seed: u64,
    sources: &Sources,
    scene: &Path,
) -> Shape {
    match kind {
        "mesh" => {
            let sp = o.span_of(F::Object::path);
            let rel = o.opt_str(cx, F::Object::path).unwrap_or_default();
            if !o.has(F::Object::path) {
                cx.push(
                    Diagnostic::error("E0280", "a mesh object needs a `path`")
                        .label(o.span, "no `path`")
                        .help("give the mesh file relative to this scene file: `path = \"assets/amphora.glb\"`"),
                );
            }
            // `texture = false`: the file's colours are never read, nor the files they name.
            let want = o
                .has(F::Object::texture)
                .then(|| o.bool(cx, F::Object::texture, true));
            let (resolved, has_texture) =
                resolve_asset(cx, &rel, sp, sources, scene, want != Some(false));
            let textured = want.unwrap_or(has_texture);
            if textured && o.has(F::Object::pattern) {
                let at = o.key_span(F::Object::pattern);
                cx.push(
                    Diagnostic::error("E0295", "a textured mesh cannot take a pattern")
                        .label(at, "the mesh's file gives its colours")
                        .help("remove `pattern`, or set `texture = false` to draw the pattern over one plain albedo"),
                );
            }
            let (offset, up_axis) = super::georef::keys(cx, o, sources, scene);
            Shape::Mesh {
                path: resolved,
                textured,
                offset,
                up_axis,
            }
        }
        "plane" => {
            let w = o.f64(cx, F::Object::width, Dim::Length, 1.0);
            let h = o.f64(cx, F::Object::height, Dim::Length, 1.0);
            check::positive(cx, o, F::Object::width, w, "m");
            check::positive(cx, o, F::Object::height, h, "m");
            Shape::Plane {
                width: w,
                height: h,
            }
        }
        "box" => {
            let size = o.vec3(cx, F::Object::size, Dim::Length, DVec3::ONE);
            if !(size.min_element() > 0.0) {
                let sp = o.span_of(F::Object::size);
                cx.push(
                    Diagnostic::error("E0281", "a box needs a positive size")
                        .label(sp, "every side must be > 0")
                        .help("e.g. `size = [1, 0.5, 0.3]` (metres)"),
                );
            }
            Shape::Box { size }
        }
        "sphere" => {
            let r = o.f64(cx, F::Object::radius, Dim::Length, 0.5);
            check::positive(cx, o, F::Object::radius, r, "m");
            Shape::Sphere { radius: r }
        }
        "cylinder" => {
            let r = o.f64(cx, F::Object::radius, Dim::Length, 0.5);
            let h = o.f64(cx, F::Object::height, Dim::Length, 1.0);
            check::positive(cx, o, F::Object::radius, r, "m");
            check::positive(cx, o, F::Object::height, h, "m");
            Shape::Cylinder {
                radius: r,
                height: h,
            }
        }
        "seabed" => seabed(cx, o, seed),
        "coral" => super::coral::shape(cx, o, seed),
        _ => boulders(cx, o, seed),
    }
}

/// A generated seabed heightfield of `width` × `length`, with `roughness` sampled every
/// `resolution` (at most 50 million cells).
fn seabed(cx: &mut Cx, o: &mut Tab, seed: u64) -> Shape {
    let width = o.f64(cx, F::Object::width, Dim::Length, 20.0);
    let length = o.f64(cx, F::Object::length, Dim::Length, 20.0);
    let roughness = o.f64(cx, F::Object::roughness, Dim::Length, 0.1);
    let resolution = o.f64(cx, F::Object::resolution, Dim::Length, 0.05);
    check::positive(cx, o, F::Object::width, width, "m");
    check::positive(cx, o, F::Object::length, length, "m");
    check::positive(cx, o, F::Object::resolution, resolution, "m");
    if roughness < 0.0 {
        check::positive(cx, o, F::Object::roughness, roughness, "m");
    }
    if width > 0.0
        && length > 0.0
        && resolution > 0.0
        && (width / resolution) * (length / resolution) > 5e7
    {
        let sp = o.span_of(F::Object::resolution);
        cx.push(
            Diagnostic::error("E0282", "the seabed heightfield is too fine")
                .label(
                    sp,
                    format!("{:.0} cells", (width / resolution) * (length / resolution)),
                )
                .help("keep width/resolution × length/resolution under 50 million cells"),
        );
    }
    Shape::Seabed {
        width,
        length,
        roughness,
        resolution,
        seed,
        relief: vec![],
    }
}

/// A seabed's `relief_file`: its points moved by `relief_origin` into the world, then into the
/// seabed's own frame (pose and scale undone), checked to make a surface
/// ([`crate::geometry::relief`]).
fn relief_points(
    cx: &mut Cx,
    o: &mut Tab,
    pose: &Pose,
    scale: DVec3,
    sources: &Sources,
    scene: &Path,
) -> Vec<DVec3> {
    let origin = o
        .opt_vec3(cx, F::Object::relief_origin, Dim::Length)
        .unwrap_or(DVec3::ZERO);
    let fspan = o.span_of(F::Object::relief_file);
    let Some(rel) = o.opt_str(cx, F::Object::relief_file) else {
        return vec![];
    };
    let pts = crate::scene::points_file::read_named(cx, sources, scene, &rel, fspan);
    if pts.is_empty() {
        return vec![];
    }
    if !(scale.min_element() > 0.0) {
        return vec![];
    }
    let to_local = pose.inverse();
    let local: Vec<DVec3> = pts
        .iter()
        .map(|p| to_local.transform_point(origin + p.p) / scale)
        .collect();
    if let Err(e) = crate::geometry::relief::Relief::through(&local) {
        cx.push(
            Diagnostic::error("E0302", "the seabed's relief points make no surface")
                .label(fspan, e)
                .help("give at least 3 points (at most 200) spread across the site, not on one line, each (x, y) once"),
        );
        return vec![];
    }
    local
}

/// `count` boulders of about `radius` scattered over `width` × `length`.
fn boulders(cx: &mut Cx, o: &mut Tab, seed: u64) -> Shape {
    let width = o.f64(cx, F::Object::width, Dim::Length, 20.0);
    let length = o.f64(cx, F::Object::length, Dim::Length, 20.0);
    let count = o.u32(cx, F::Object::count, 30);
    let radius = o.f64(cx, F::Object::radius, Dim::Length, 0.3);
    let count = check::capped(cx, o, F::Object::count, count, 1_000_000, "boulders", 0);
    check::positive(cx, o, F::Object::width, width, "m");
    check::positive(cx, o, F::Object::length, length, "m");
    check::positive(cx, o, F::Object::radius, radius, "m");
    Shape::Boulders {
        width,
        length,
        count,
        radius,
        seed,
    }
}

/// The mesh file `rel`, relative to the scene file that names it: it must be a readable glTF,
/// OBJ or PLY file inside the scene's folder, a regular file of at most
/// [`MAX_MESH_BYTES`](crate::scene::source::MAX_MESH_BYTES) read the front end's one way
/// ([`read_capped`]), and so must every file it names (a `.gltf`'s buffers and images, an OBJ's
/// MTL files and their images: [`crate::geometry::meshfile::probe`]); every image's header is
/// read and its size checked (unless `colours` is false: then only the geometry will be read).
/// Returns its canonical path (the joined path after an error) and whether the file carries
/// colours of its own (an image texture or vertex colours).
fn resolve_asset(
    cx: &mut Cx,
    rel: &str,
    span: Span,
    sources: &Sources,
    scene: &Path,
    colours: bool,
) -> (String, bool) {
    use crate::scene::source::{
        MAX_MESH_BYTES, Refusal, display, outside_diag, outside_root, read_capped,
    };
    if rel.is_empty() {
        return (String::new(), false);
    }
    let dir = sources
        .dir_of(span.file)
        .unwrap_or_else(|| scene.parent().map(Path::to_path_buf).unwrap_or_default());
    let p = dir.join(rel);
    if let Some(why) = outside_root(sources, rel, &p) {
        cx.push(outside_diag(rel, &why, span));
        return (display(&p), false);
    }
    let format = crate::geometry::meshfile::Format::of(&p);
    let ext = p
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    let mut textured = false;
    match read_capped(&p, MAX_MESH_BYTES) {
        Ok(bytes) => {
            // The model carries the canonical path, so every backend finds the file
            // wherever it runs from; it must stay inside the scene's directory tree.
            let canon = p.canonicalize().unwrap_or_else(|_| p.clone());
            let roots: Vec<std::path::PathBuf> =
                [Some(dir.clone()), scene.parent().map(Path::to_path_buf)]
                    .into_iter()
                    .flatten()
                    .filter_map(|d| {
                        (if d.as_os_str().is_empty() {
                            Path::new(".").to_path_buf()
                        } else {
                            d
                        })
                        .canonicalize()
                        .ok()
                    })
                    .collect();
            let inside = roots.iter().any(|r| canon.starts_with(r));
            if format.is_none() {
                cx.push(
                    Diagnostic::error("E0285", "meshes must be glTF, OBJ or PLY files")
                        .label(span, format!("`.{ext}` file"))
                        .help("convert the mesh to glTF (`.glb` or `.gltf`), OBJ or PLY, e.g. with Blender's exporters"),
                );
            } else if format == Some(crate::geometry::meshfile::Format::Gltf)
                && let Err(e) = crate::geometry::meshfile::parse_gltf(&bytes)
                    .and_then(|g| {
                        gltf_side_files(&g, p.parent().unwrap_or(Path::new(".")), sources)
                    })
                    .map(|files| cx.files.extend(files))
            {
                cx.push(
                    Diagnostic::error(
                        "E0287",
                        format!("`{}` is not a readable glTF file", display(&p)),
                    )
                    .label(span, e)
                    .help("re-export the mesh as glTF 2.0 (`.glb`), e.g. from Blender"),
                );
            } else if inside && !colours {
                cx.files.push(p.clone());
            } else if inside {
                match side_files(&bytes, &canon, &roots, sources) {
                    Ok((files, t)) => {
                        cx.files.push(p.clone());
                        cx.files.extend(files);
                        textured = t;
                    }
                    Err(e) => cx.push(
                        Diagnostic::error(
                            "E0289",
                            format!("a file the mesh `{}` names is refused", display(&p)),
                        )
                        .label(span, e)
                        .help("keep the mesh's MTL files and images beside it, named by relative paths inside the scene's folder, as PNG, JPEG or OpenEXR of at most 16384 pixels a side"),
                    ),
                }
            }
            if !inside {
                cx.push(
                    Diagnostic::error("E0286", "the mesh file is outside the scene's directory")
                        .label(span, "this path leaves the directory of the scene")
                        .help("keep assets next to the scene (e.g. `assets/wreck.glb`) so the scene can be shared as one folder"),
                );
            }
            return (canon.to_string_lossy().to_string(), textured);
        }
        Err(Refusal::NotAFile(what)) => cx.push(
            Diagnostic::error("E0284", format!("`{}` is not a file", display(&p)))
                .label(span, what)
                .help("give the path of the mesh file itself; folders, devices and named pipes are never read"),
        ),
        Err(r @ Refusal::TooLarge { .. }) => cx.push(
            Diagnostic::error("E0284", format!("mesh file `{}` is too large", display(&p)))
                .label(span, r.reason())
                .help("decimate the mesh (e.g. Blender's Decimate modifier) and export it again as `.glb`"),
        ),
        Err(Refusal::Unreadable(why)) => cx.push(
            Diagnostic::error("E0284", format!("mesh file `{}` not found", display(&p)))
                .label(span, why)
                .help("paths are relative to the scene file that names them"),
        ),
    }
    (crate::scene::source::display(&p), textured)
}

/// The files a mesh names ([`crate::geometry::meshfile::probe`]), each inside the pack when
/// there is one, and every image's header read and its size checked
/// ([`crate::texture::mapped::probe`]); returns them and whether the mesh carries colours of
/// its own.
fn side_files(
    bytes: &[u8],
    mesh: &Path,
    roots: &[std::path::PathBuf],
    sources: &Sources,
) -> Result<(Vec<std::path::PathBuf>, bool), String> {
    use crate::geometry::meshfile::ImageSource;
    let probe = crate::geometry::meshfile::probe(bytes, mesh, roots)?;
    // Side files are canonical paths: inside a pack they must be below its folder.
    if let Some(root) = &sources.root
        && let Some(f) = probe.side_files.iter().find(|f| !f.starts_with(root))
    {
        return Err(format!("`{}` is outside the pack", f.display()));
    }
    for img in &probe.images {
        let shown = img.shown();
        match &img.source {
            ImageSource::File(f) => {
                let b = crate::geometry::meshfile::read(f)?;
                crate::texture::mapped::probe(&b, &shown)?;
            }
            ImageSource::Bytes(b) => {
                crate::texture::mapped::probe(b, &shown)?;
            }
        }
    }
    Ok((probe.side_files, probe.textured))
}

/// `albedo` and an optional `[….pattern]` texture (checker, noise, fbm, sand, rock, coral)
/// with its `variation` and `texel`.
fn material(cx: &mut Cx, o: &mut Tab, default_albedo: f64) -> Material {
    let albedo = o.rgb(cx, F::Object::albedo, Dim::Number, [default_albedo; 3]);
    if albedo.iter().any(|a| !(0.0..=1.0).contains(a)) {
        let sp = o.span_of(F::Object::albedo);
        cx.push(
            Diagnostic::error("E0290", "albedo must be between 0 and 1")
                .label(sp, "outside [0, 1]")
                .help("albedo is the fraction of light reflected: 0.05 black ink, 0.9 white paper"),
        );
    }
    let mut variation = 0.0;
    let mut texel = None;
    let mut grid = None;
    let pattern = o.get(F::Object::pattern).map(|n| {
        let mut p = Tab::open(cx, Some(n), &o.full(F::Object::pattern), n.span);
        let ty = p
            .choice(
                cx,
                F::PatternTable::kind,
                &["checker", "noise", "fbm", "sand", "rock", "coral"],
            )
            .unwrap_or("noise");
        let seed = |cx: &mut Cx, p: &mut Tab| p.opt_u64(cx, F::PatternTable::seed).unwrap_or(0);
        // A length ≥ 0 (0 switches the feature off).
        let len0 = |cx: &mut Cx, p: &mut Tab, key: &'static str, default: f64| {
            let v = p.f64(cx, key, Dim::Length, default);
            check::non_negative(cx, p, key, v, "m");
            v
        };
        let len = |cx: &mut Cx, p: &mut Tab, key: &'static str, default: f64| {
            let v = p.f64(cx, key, Dim::Length, default);
            check::positive(cx, p, key, v, "m");
            v
        };
        let fraction = |cx: &mut Cx, p: &mut Tab, key: &'static str, default: f64| {
            let v = p.f64(cx, key, Dim::Number, default);
            check::within(cx, p, key, v, 0.0, 1.0);
            v
        };
        let r = match ty {
            "checker" => Pattern::Checker {
                size: len(cx, &mut p, F::PatternTable::size, 0.1),
                contrast: p.f64(cx, F::PatternTable::contrast, Dim::Number, 0.5),
            },
            "fbm" => Pattern::Fbm {
                size: len(cx, &mut p, F::PatternTable::size, 1.0),
                smallest: len0(cx, &mut p, F::PatternTable::smallest, 0.0),
                gain: fraction(cx, &mut p, F::PatternTable::gain, 0.7),
                contrast: fraction(cx, &mut p, F::PatternTable::contrast, 0.3),
                seed: seed(cx, &mut p),
            },
            "sand" => Pattern::Sand {
                wavelength: len0(cx, &mut p, F::PatternTable::wavelength, 0.1),
                direction: p.f64(cx, F::PatternTable::direction, Dim::Angle, 0.0),
                ripple: fraction(cx, &mut p, F::PatternTable::ripple, 0.15),
                grain: len0(cx, &mut p, F::PatternTable::grain, 0.0005),
                contrast: fraction(cx, &mut p, F::PatternTable::contrast, 0.2),
                seed: seed(cx, &mut p),
            },
            "rock" => Pattern::Rock {
                size: len(cx, &mut p, F::PatternTable::size, 0.5),
                crack: len0(cx, &mut p, F::PatternTable::crack, 0.2),
                crack_width: len0(cx, &mut p, F::PatternTable::crack_width, 0.003),
                speckle: len0(cx, &mut p, F::PatternTable::speckle, 0.002),
                contrast: fraction(cx, &mut p, F::PatternTable::contrast, 0.25),
                seed: seed(cx, &mut p),
            },
            "coral" => {
                let size = len(cx, &mut p, F::PatternTable::size, 0.3);
                let cover = fraction(cx, &mut p, F::PatternTable::cover, 0.6);
                let colors = coral_colors(cx, &mut p);
                Pattern::Coral {
                    size,
                    cover,
                    colors,
                    polyp: len0(cx, &mut p, F::PatternTable::polyp, 0.005),
                    contrast: fraction(cx, &mut p, F::PatternTable::contrast, 0.2),
                    seed: seed(cx, &mut p),
                }
            }
            _ => Pattern::Noise {
                size: len(cx, &mut p, F::PatternTable::size, 0.1),
                amount: p.f64(cx, F::PatternTable::amount, Dim::Number, 0.5),
                seed: seed(cx, &mut p),
            },
        };
        if ty != "checker" {
            variation = fraction(cx, &mut p, F::PatternTable::variation, 0.0);
            texel = p.opt_f64(cx, F::PatternTable::texel, Dim::Length);
            if let Some(t) = texel {
                check::positive(cx, &p, F::PatternTable::texel, t, "m");
            }
            if let Some(spacing) = p.opt_f64(cx, F::PatternTable::grid, Dim::Length) {
                check::positive(cx, &p, F::PatternTable::grid, spacing, "m");
                let width = len(cx, &mut p, F::PatternTable::grid_width, 0.01);
                let albedo = p.rgb(cx, F::PatternTable::grid_albedo, Dim::Number, GRID_ALBEDO);
                if albedo.iter().any(|a| !(0.0..=1.0).contains(a)) {
                    let sp = p.span_of(F::PatternTable::grid_albedo);
                    cx.push(
                        Diagnostic::error("E0290", "albedo must be between 0 and 1")
                            .label(sp, "outside [0, 1]")
                            .help("a white string's albedo is about 0.8"),
                    );
                }
                grid = Some(crate::model::Grid {
                    spacing,
                    width,
                    albedo,
                });
            }
        }
        p.finish_as(cx, Some(&format!("a {ty} pattern")));
        r
    });
    Material {
        albedo,
        pattern,
        variation,
        texel,
        grid,
        glass: None,
        fill: None,
    }
}

/// `glass = "N-BK7"`: the object is a clear glass solid ([`crate::model::Material::glass`]).
/// A box (a tank's window, an acrylic block), a sphere (a ball lens, a float) or a cylinder
/// (a rod, a viewing port's plug), each exact in all three back ends: native intersects glass
/// spheres and cylinders analytically, Mitsuba has its own `sphere` and `cylinder`, Cycles
/// finely tessellated ones with their true normals. A sphere must be scaled uniformly and a
/// cylinder alike across its axis (Mitsuba's shapes take no other scale). A mesh or a plane
/// would refract at flat facets, differently in each back end. A glass object takes no
/// `albedo` or `pattern`.
fn glass(cx: &mut Cx, o: &mut Tab, shape_kind: &str, scale: DVec3) -> Option<crate::model::Glass> {
    let span = o.span_of(F::Object::glass);
    let name = o.opt_str(cx, F::Object::glass)?;
    let Some(g) = super::camera::catalogue_glass(&name) else {
        let d = Diagnostic::error("E0299", format!("unknown glass `{name}`")).label(
            span,
            format!("catalogue: {}", crate::optics::glass::CATALOGUE.join(", ")),
        );
        let d = match crate::scene::reader::did_you_mean(
            &name,
            crate::optics::glass::CATALOGUE.iter().copied(),
        ) {
            Some(s) => d.help(format!("did you mean `{s}`?")),
            None => d.help("pick a catalogue glass: `glass = \"N-BK7\"` or `\"PMMA\"` (acrylic)"),
        };
        cx.push(d);
        return None;
    };
    if !solid_checks(cx, o, shape_kind, scale, span, "glass") {
        return None;
    }
    Some(g)
}

/// `fill = { … }`: the object is filled with water ([`crate::model::Material::fill`]), its
/// faces the boundary of that water's index. The same shapes as glass, and not both.
fn fill(
    cx: &mut Cx,
    o: &mut Tab,
    shape_kind: &str,
    scale: DVec3,
    site: &Site,
) -> Option<crate::model::Water> {
    let node = o.get(F::Object::fill)?;
    let span = o.key_span(F::Object::fill);
    let path = o.full(F::Object::fill);
    let water = super::environment::fill_water(cx, node, &path, site);
    if o.has(F::Object::glass) {
        cx.push(
            Diagnostic::error("E0303", "an object is either glass or filled, not both")
                .label(span, "filled here")
                .label(o.key_span(F::Object::glass), "and glass here")
                .help(
                    "a glass tank of water is two objects: the water (`fill`) and the glass \
                     walls or window (`glass`) beside it",
                ),
        );
        return None;
    }
    if !solid_checks(cx, o, shape_kind, scale, span, "filled") {
        return None;
    }
    Some(water)
}

/// The rules a glass or filled object's shape keeps (`what`: "glass" or "filled"; `span`: its
/// key's): a box, a sphere scaled uniformly or a cylinder scaled alike across its axis (E0296,
/// E0301), and no `albedo` or `pattern` (E0292). Returns whether the shape is usable.
fn solid_checks(
    cx: &mut Cx,
    o: &mut Tab,
    shape_kind: &str,
    scale: DVec3,
    span: Span,
    what: &str,
) -> bool {
    let what_key = if what == "glass" { "glass" } else { "fill" };
    if !matches!(shape_kind, "box" | "sphere" | "cylinder") {
        cx.push(
            Diagnostic::error(
                "E0296",
                format!("a {what} object must be a box, a sphere or a cylinder"),
            )
            .label(span, format!("on a {shape_kind}"))
            .help(
                "make it `shape = \"box\"` (a window, a slab, a block), `\"sphere\"` or \
                     `\"cylinder\"`; other glass shapes would refract at the flat facets of \
                     their meshes",
            ),
        );
        return false;
    }
    let uneven = match shape_kind {
        "sphere" => scale.max_element() > scale.min_element(),
        "cylinder" => scale.x != scale.y,
        _ => false,
    };
    if uneven {
        cx.push(
            Diagnostic::error(
                "E0301",
                format!("a {what} sphere or cylinder must be round"),
            )
            .label(
                o.span_of(F::Object::scale),
                format!("scaled by {} × {} × {}", scale.x, scale.y, scale.z),
            )
            .help(
                "scale a sphere alike on all three axes and a cylinder alike on x and y, \
                     or set the `radius`; glass ellipsoids and elliptic cylinders are not \
                     supported",
            ),
        );
        return false;
    }
    for key in [F::Object::albedo, F::Object::pattern] {
        if o.has(key) {
            let sp = o.key_span(key);
            cx.push(
                Diagnostic::error("E0292", format!("a {what} object has no `{key}`"))
                    .label(
                        sp,
                        if what == "glass" {
                            "clear glass reflects and refracts; it has no colour"
                        } else {
                            "its faces are its water's boundary; it has no colour"
                        },
                    )
                    .help(format!(
                        "remove `{key}`, or `{what_key}` for an opaque object"
                    )),
            );
        }
    }
    true
}

/// Default albedo of a pattern's grid lines: a pale yellow string.
const GRID_ALBEDO: crate::model::Rgb = [0.8, 0.75, 0.5];

/// `colors = [[r, g, b], …]` of a coral pattern: albedos in [0, 1]; empty = the default palette.
fn coral_colors(cx: &mut Cx, p: &mut Tab) -> Vec<crate::model::Rgb> {
    let full = p.full(F::PatternTable::colors);
    let Some(n) = p.get(F::PatternTable::colors) else {
        return vec![];
    };
    let Val::Array(items) = &n.val else {
        cx.push(crate::scene::reader::type_error(
            n,
            &full,
            "a list of [r, g, b] albedos",
            &n.val,
        ));
        return vec![];
    };
    let mut out = Vec::new();
    for (i, item) in items.iter().enumerate() {
        let Some(v) =
            crate::scene::reader::vector(cx, item, Dim::Number, &format!("{full}.{i}"), Some(3))
        else {
            continue;
        };
        if v.iter().any(|a| !(0.0..=1.0).contains(a)) {
            cx.push(
                Diagnostic::error("E0290", "albedo must be between 0 and 1")
                    .label(item.span, "outside [0, 1]")
                    .help("each colour is an albedo `[r, g, b]` with values in [0, 1]"),
            );
            continue;
        }
        out.push([v[0], v[1], v[2]]);
    }
    out
}

/// Every file a `.gltf` refers to (buffers, images) must be a relative path to a regular file
/// of at most [`MAX_ASSET_BYTES`](crate::scene::source::MAX_ASSET_BYTES) beside it, inside the
/// pack when there is one: the mesh loader reads them later, and must never read a device, a
/// named pipe or a file outside the scene. Returns them (a pack carries them with the scene).
fn gltf_side_files(
    g: &gltf::Gltf,
    dir: &Path,
    sources: &Sources,
) -> Result<Vec<std::path::PathBuf>, String> {
    use crate::scene::source::{MAX_ASSET_BYTES, outside_root};
    let uris = g
        .buffers()
        .filter_map(|b| match b.source() {
            gltf::buffer::Source::Uri(u) => Some(u),
            gltf::buffer::Source::Bin => None,
        })
        .chain(g.images().filter_map(|i| match i.source() {
            gltf::image::Source::Uri { uri, .. } => Some(uri),
            gltf::image::Source::View { .. } => None,
        }));
    let mut files = Vec::new();
    for uri in uris {
        if uri.starts_with("data:") {
            continue;
        }
        let rel = crate::geometry::meshfile::percent_decoded(uri);
        let path = Path::new(&rel);
        if uri.contains(':') || path.is_absolute() || path.has_root() {
            return Err(format!(
                "refers to `{uri}`, which is not a path relative to the glTF file"
            ));
        }
        let full = dir.join(path);
        if let Some(why) = outside_root(sources, &rel, &full) {
            return Err(format!("refers to `{uri}`: {why}, outside the pack"));
        }
        match std::fs::metadata(&full) {
            Ok(m) if m.is_file() && m.len() <= MAX_ASSET_BYTES => files.push(full),
            Ok(m) if m.is_file() => {
                return Err(format!(
                    "refers to `{uri}`, larger than {}",
                    crate::scene::source::size_text(MAX_ASSET_BYTES)
                ));
            }
            Ok(_) => return Err(format!("refers to `{uri}`, which is not a regular file")),
            Err(_) => return Err(format!("refers to `{uri}`, which is missing")),
        }
    }
    Ok(files)
}

//! Image textures of mesh files (`shape = "mesh"` with its file's colours): decoding, the
//! mipmap level every backend samples, and the prepared mesh the backends draw.
//!
//! | step | what |
//! |---|---|
//! | read | the mesh file ([`crate::geometry::meshfile`]): geometry, texture coordinates, vertex colours, one material per triangle |
//! | decode | PNG, JPEG or OpenEXR, at most [`MAX_TEXTURE_SIDE`] texels a side and [`MAX_DECODE_BYTES`] decoded (checked on the header before anything is decoded: a "decompression bomb" that claims 100 000² pixels is refused at once); 8- and 16-bit images are sRGB and decoded to linear, float images are linear; alpha is ignored |
//! | level | the texel size on the surface (√(area / texels), over the triangles of the material) and the texel wanted, half the finest ground sample distance of the cameras on the object ([`super::bake::wanted_texel`], the rule of baked textures); the image is halved (2 × 2 box average, in linear light) while its texel stays at most the wanted one |
//! | colour | the chosen level times the material's colour factor (MTL `Kd`, glTF `baseColorFactor`), clamped to [0, 1], stored as 16-bit linear values |
//! | sample | bilinear between texel centres ((i + ½)/W, (j + ½)/H), wrapping as the material says (repeat, clamp, mirror): [`Image16::sample`] |
//!
//! Mitsuba and Cycles receive this same level as a 16-bit linear PNG (`raw`, Non-Color) with
//! bilinear filtering and the same wrap, so the three backends sample the same texels the same
//! way. A pixel that sees several texels of the chosen level averages them through the
//! renderer's pixel samples (every backend jitters its samples over the pixel), as for baked
//! textures: the level removes the detail a pixel can never show, the samples the rest.
//! Prepared meshes are cached by content while any user holds them.

use crate::geometry::mesh::TriMesh;
use crate::geometry::meshfile::{FileMaterial, ImageSource, MeshFile, Wrap};
use crate::model::{Model, Object, Shape};
use glam::DVec3;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock, Weak};

pub use crate::io::read::MAX_TEXTURE_SIDE;
/// Most bytes a decoder may allocate for one image (a 16384² RGBA 8-bit image).
pub const MAX_DECODE_BYTES: u64 = 1 << 30;

/// An RGB image of linear values × 65535, row-major from row 0 (v = 0), with its wrap mode.
#[derive(Debug, Clone, PartialEq)]
pub struct Image16 {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<u16>,
    pub wrap: Wrap,
}

impl Image16 {
    fn index(&self, i: i64, n: u32) -> usize {
        super::mip::wrapped(self.wrap, i, n)
    }

    fn texel(&self, i: i64, j: i64) -> [f64; 3] {
        let i = self.index(i, self.width);
        let j = self.index(j, self.height);
        let k = 3 * (j * self.width as usize + i);
        [0, 1, 2].map(|c| self.rgb[k + c] as f64 / 65535.0)
    }

    /// Bilinear lookup at (u, v), texel centres at ((i + ½)/W, (j + ½)/H), wrapping by
    /// [`Image16::wrap`]: Mitsuba's `bitmap` (`filter_type = bilinear`) and Cycles' Image
    /// Texture (`Linear`) with the same wrap.
    pub fn sample(&self, u: f64, v: f64) -> [f64; 3] {
        super::bilinear(self.width, self.height, u, v, |i, j| self.texel(i, j))
    }

    /// Mean of every texel, per channel.
    pub fn mean(&self) -> [f64; 3] {
        let n = (self.width as f64 * self.height as f64).max(1.0);
        let mut s = [0u64; 3];
        for px in self.rgb.chunks_exact(3) {
            for c in 0..3 {
                s[c] += px[c] as u64;
            }
        }
        s.map(|v| v as f64 / 65535.0 / n)
    }

    /// The next mipmap level: 2 × 2 box average (an odd last row or column averages with
    /// itself), rounded.
    pub fn half(&self) -> Image16 {
        let (w, h) = (
            self.width.div_ceil(2).max(1),
            self.height.div_ceil(2).max(1),
        );
        let mut rgb = vec![0u16; 3 * w as usize * h as usize];
        let at = |i: u32, j: u32, c: usize| {
            let i = i.min(self.width - 1) as usize;
            let j = j.min(self.height - 1) as usize;
            self.rgb[3 * (j * self.width as usize + i) + c] as u32
        };
        use rayon::prelude::*;
        rgb.par_chunks_mut(3 * w as usize)
            .enumerate()
            .for_each(|(j, row)| {
                let j = j as u32;
                for i in 0..w {
                    for c in 0..3 {
                        let s = at(2 * i, 2 * j, c)
                            + at(2 * i + 1, 2 * j, c)
                            + at(2 * i, 2 * j + 1, c)
                            + at(2 * i + 1, 2 * j + 1, c);
                        row[3 * i as usize + c] = ((s + 2) / 4) as u16;
                    }
                }
            });
        Image16 {
            width: w,
            height: h,
            rgb,
            wrap: self.wrap,
        }
    }

    /// The image as a 16-bit RGB PNG of linear values (not sRGB); deterministic bytes.
    pub fn png(&self) -> Result<Vec<u8>, String> {
        use image::ImageEncoder;
        let mut out = Vec::new();
        let bytes: Vec<u8> = self.rgb.iter().flat_map(|v| v.to_ne_bytes()).collect();
        image::codecs::png::PngEncoder::new_with_quality(
            &mut out,
            image::codecs::png::CompressionType::Fast,
            image::codecs::png::FilterType::Sub,
        )
        .write_image(
            &bytes,
            self.width,
            self.height,
            image::ExtendedColorType::Rgb16,
        )
        .map_err(|e| format!("cannot encode a texture: {e}"))?;
        Ok(out)
    }
}

/// An image reader for `bytes` with poser's limits; `sides`: with the limit on the sides too
/// (without, reading the header tells what it claims, which [`check_size`] then judges).
fn reader(bytes: &[u8], sides: bool) -> Result<image::ImageReader<std::io::Cursor<&[u8]>>, String> {
    let mut r = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| e.to_string())?;
    let mut limits = image::Limits::default();
    if sides {
        limits.max_image_width = Some(MAX_TEXTURE_SIDE);
        limits.max_image_height = Some(MAX_TEXTURE_SIDE);
    }
    limits.max_alloc = Some(MAX_DECODE_BYTES);
    r.limits(limits);
    Ok(r)
}

/// The size an image's header claims, refused beyond [`MAX_TEXTURE_SIDE`] or when the header
/// cannot be read. Reads the header only.
pub fn probe(bytes: &[u8], shown: &str) -> Result<(u32, u32), String> {
    let r = reader(bytes, false).map_err(|e| format!("cannot read {shown}: {e}"))?;
    if r.format().is_none() {
        return Err(format!("{shown} is not a PNG, JPEG or OpenEXR image"));
    }
    let (w, h) = r
        .into_dimensions()
        .map_err(|e| format!("cannot read {shown}: {e}"))?;
    check_size(w, h, shown)?;
    Ok((w, h))
}

fn check_size(w: u32, h: u32, shown: &str) -> Result<(), String> {
    if w == 0 || h == 0 {
        return Err(format!("{shown} is empty ({w}×{h} pixels)"));
    }
    if w > MAX_TEXTURE_SIDE || h > MAX_TEXTURE_SIDE {
        return Err(format!(
            "{shown} claims {w}×{h} pixels, more than the {MAX_TEXTURE_SIDE} a side a texture \
             may have (a damaged file, or a decompression bomb): it is not decoded"
        ));
    }
    Ok(())
}

/// sRGB 8-bit → linear × 65535.
fn lut8() -> &'static [u16; 256] {
    static L: OnceLock<[u16; 256]> = OnceLock::new();
    L.get_or_init(|| {
        std::array::from_fn(|i| {
            (crate::geometry::meshfile::srgb_to_linear(i as f64 / 255.0) * 65535.0).round() as u16
        })
    })
}

/// sRGB 16-bit → linear × 65535.
fn lut16() -> &'static [u16] {
    static L: OnceLock<Vec<u16>> = OnceLock::new();
    L.get_or_init(|| {
        (0..=65535u32)
            .map(|i| {
                (crate::geometry::meshfile::srgb_to_linear(i as f64 / 65535.0) * 65535.0).round()
                    as u16
            })
            .collect()
    })
}

/// Decode an image to linear 16-bit RGB: 8- and 16-bit images are sRGB, float images linear
/// (clamped to [0, 1]); grey is replicated, alpha ignored.
pub fn decode(bytes: &[u8], shown: &str, wrap: Wrap) -> Result<Image16, String> {
    probe(bytes, shown)?;
    let img = reader(bytes, true)
        .and_then(|r| r.decode().map_err(|e| e.to_string()))
        .map_err(|e| format!("cannot decode {shown}: {e}"))?;
    let (w, h) = (img.width(), img.height());
    check_size(w, h, shown)?;
    use image::DynamicImage as D;
    let rgb: Vec<u16> = match img {
        D::ImageRgb8(b) => b.into_raw().iter().map(|&v| lut8()[v as usize]).collect(),
        D::ImageRgba8(b) => b
            .into_raw()
            .chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]].map(|v| lut8()[v as usize]))
            .collect(),
        D::ImageLuma8(b) => b
            .into_raw()
            .iter()
            .flat_map(|&v| [lut8()[v as usize]; 3])
            .collect(),
        D::ImageLumaA8(b) => b
            .into_raw()
            .chunks_exact(2)
            .flat_map(|p| [lut8()[p[0] as usize]; 3])
            .collect(),
        D::ImageRgb16(b) => b.into_raw().iter().map(|&v| lut16()[v as usize]).collect(),
        D::ImageRgba16(b) => b
            .into_raw()
            .chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]].map(|v| lut16()[v as usize]))
            .collect(),
        D::ImageLuma16(b) => b
            .into_raw()
            .iter()
            .flat_map(|&v| [lut16()[v as usize]; 3])
            .collect(),
        D::ImageLumaA16(b) => b
            .into_raw()
            .chunks_exact(2)
            .flat_map(|p| [lut16()[p[0] as usize]; 3])
            .collect(),
        other => {
            let f = other.into_rgb32f();
            f.into_raw()
                .iter()
                .map(|&v| {
                    let v = if v.is_finite() {
                        v.clamp(0.0, 1.0)
                    } else {
                        0.0
                    };
                    (v as f64 * 65535.0).round() as u16
                })
                .collect()
        }
    };
    Ok(Image16 {
        width: w,
        height: h,
        rgb,
        wrap,
    })
}

/// How one material of a prepared mesh colours its triangles.
#[derive(Debug, Clone)]
pub enum Look {
    /// One linear albedo.
    Color([f64; 3]),
    /// The image level chosen, colour factor applied.
    Image(Arc<Image16>),
    /// The mesh's per-vertex colours.
    VertexColors,
}

/// The plan of one material: where its colour comes from and, for an image, the level chosen.
#[derive(Debug, Clone)]
pub struct MaterialPlan {
    pub name: String,
    pub triangles: usize,
    /// The image and who names it (for messages); `None` without one.
    pub image: Option<String>,
    /// Full-size image, texels.
    pub size: (u32, u32),
    /// Texel of the full-size image on the surface, m (0 when unknown: no area or no UVs).
    pub texel0: f64,
    /// Mipmap level chosen (0: full size), its size and texel, m.
    pub level: u32,
    pub level_size: (u32, u32),
    pub texel: f64,
}

/// What a textured mesh object will be, without decoding any image: for `poser explain` and
/// for [`prepare_object`].
#[derive(Debug, Clone)]
pub struct MeshPlan {
    /// The file read, its vertices in the object frame (offset and up axis applied:
    /// [`crate::geometry::mesh::georeferenced`]).
    pub file: MeshFile,
    pub materials: Vec<MaterialPlan>,
    /// Texel wanted, m, and why (half the finest GSD).
    pub wanted: f64,
    pub reason: String,
}

impl MeshPlan {
    /// Texels of the chosen levels (each image once).
    pub fn texels(&self) -> u64 {
        let mut seen: Vec<(&str, u32)> = Vec::new();
        let mut n = 0;
        for m in &self.materials {
            if let Some(img) = &m.image
                && !seen.contains(&(img.as_str(), m.level))
            {
                seen.push((img.as_str(), m.level));
                n += m.level_size.0 as u64 * m.level_size.1 as u64;
            }
        }
        n
    }

    /// Memory the native renderer takes for the object, bytes: the mesh and its BVH (about
    /// 200 bytes a triangle: corners, texture coordinates, colours, nodes) and the texels of the
    /// chosen levels (6 bytes each); decoding a full-size image takes its own size for a moment
    /// more.
    pub fn memory(&self) -> u64 {
        let tris = self.file.mesh.triangles.len() as u64;
        let colors = if self.file.colors.is_empty() { 0 } else { 36 };
        tris * (200 + colors) + 6 * self.texels()
    }

    /// `poser explain`'s lines about the object.
    pub fn lines(&self) -> Vec<String> {
        let gsd = 2.0 * self.wanted;
        let mut out = vec![format!(
            "{} triangles, {} vertices, {} material(s); {} texels at the levels used; about {} in the native renderer",
            self.file.mesh.triangles.len(),
            self.file.mesh.positions.len(),
            self.materials.len(),
            self.texels(),
            crate::io::read::size_text(self.memory())
        )];
        for m in &self.materials {
            let name = if m.name.is_empty() {
                "(no material)"
            } else {
                &m.name
            };
            let line = match &m.image {
                Some(img) if m.texel0 > 0.0 => {
                    let vs = if m.texel0 > gsd {
                        format!(
                            "COARSER than the GSD ({:.2} mm): the images will be blurred by the texture",
                            gsd * 1e3
                        )
                    } else {
                        format!("finest GSD {:.2} mm", gsd * 1e3)
                    };
                    format!(
                        "  `{name}` ({} triangles): {img}, {}×{} texels of {:.2} mm; level {} used ({}×{}, {:.2} mm texels); {vs}",
                        m.triangles,
                        m.size.0,
                        m.size.1,
                        m.texel0 * 1e3,
                        m.level,
                        m.level_size.0,
                        m.level_size.1,
                        m.texel * 1e3
                    )
                }
                Some(img) => format!(
                    "  `{name}` ({} triangles): {img}, {}×{} texels (no texture area: level 0)",
                    m.triangles, m.size.0, m.size.1
                ),
                None => format!("  `{name}` ({} triangles): one colour", m.triangles),
            };
            out.push(line);
        }
        if !self.file.colors.is_empty() {
            out.push("  per-vertex colours".into());
        }
        out.push(format!(
            "  texel wanted: {:.2} mm, {}",
            self.wanted * 1e3,
            self.reason
        ));
        out
    }
}

/// The folders a model's mesh files may name side files in: the scene file's.
fn roots(model: &Model) -> (PathBuf, Vec<PathBuf>) {
    let base = Path::new(&model.source)
        .parent()
        .unwrap_or(Path::new("."))
        .to_path_buf();
    (base.clone(), vec![base])
}

/// The file of a mesh object.
fn mesh_path(o: &Object, base: &Path) -> Option<PathBuf> {
    match &o.shape {
        Shape::Mesh {
            path,
            textured: true,
            ..
        } => Some(crate::geometry::mesh::mesh_file_path(path, base)),
        _ => None,
    }
}

/// Texel of a material's image on the surface: √(area of its triangles / their texels), with
/// positions scaled by `scale`; 0 when it has no texture area.
fn surface_texel(f: &MeshFile, k: u32, scale: DVec3, size: (u32, u32)) -> f64 {
    if f.uv.is_empty() {
        return 0.0;
    }
    let (mut area, mut uv_area) = (0.0, 0.0);
    for (t, &m) in f.mesh.triangles.iter().zip(&f.material) {
        if m != k {
            continue;
        }
        let [a, b, c] = t.map(|i| f.mesh.positions[i as usize] * scale);
        area += 0.5 * (b - a).cross(c - a).length();
        let [p, q, r] = t.map(|i| f.uv[i as usize]);
        let (e1, e2) = (
            [(q[0] - p[0]) as f64, (q[1] - p[1]) as f64],
            [(r[0] - p[0]) as f64, (r[1] - p[1]) as f64],
        );
        uv_area += 0.5 * (e1[0] * e2[1] - e1[1] * e2[0]).abs();
    }
    let texels = uv_area * size.0 as f64 * size.1 as f64;
    if texels > 0.0 && area > 0.0 {
        (area / texels).sqrt()
    } else {
        0.0
    }
}

/// The plan of object `index` when it is a textured mesh (`None` otherwise): the file read,
/// every image's header probed, each material's level chosen.
pub fn plan_object(model: &Model, index: usize) -> Result<Option<MeshPlan>, String> {
    let o = &model.objects[index];
    let (base, roots) = roots(model);
    let Some(path) = mesh_path(o, &base) else {
        return Ok(None);
    };
    let err = |e: String| format!("object `{}`: {e}", o.name);
    let mut file = crate::geometry::meshfile::load(&path, &roots).map_err(err)?;
    if let Shape::Mesh {
        offset, up_axis, ..
    } = &o.shape
    {
        let format = crate::geometry::meshfile::Format::of(&path);
        crate::geometry::mesh::georeferenced(&mut file.mesh, format, *offset, *up_axis);
    }
    let (wanted, reason) = super::bake::wanted_texel(model, o, file.mesh.bounds());
    let mut materials = Vec::new();
    let mut sizes: HashMap<String, (u32, u32)> = HashMap::new();
    for (k, m) in file.materials.iter().enumerate() {
        let triangles = file.material.iter().filter(|&&x| x == k as u32).count();
        let mut plan = MaterialPlan {
            name: m.name.clone(),
            triangles,
            image: None,
            size: (0, 0),
            texel0: 0.0,
            level: 0,
            level_size: (0, 0),
            texel: 0.0,
        };
        if let Some(img) = &m.image {
            let shown = img.shown();
            let size = match sizes.get(&shown) {
                Some(&s) => s,
                None => {
                    let s = match &img.source {
                        ImageSource::File(p) => {
                            let bytes = crate::geometry::meshfile::read(p).map_err(err)?;
                            probe(&bytes, &shown).map_err(err)?
                        }
                        ImageSource::Bytes(b) => probe(b, &shown).map_err(err)?,
                    };
                    sizes.insert(shown.clone(), s);
                    s
                }
            };
            let texel0 = surface_texel(&file, k as u32, o.scale, size);
            let (mut level, mut w, mut h, mut texel) = (0, size.0, size.1, texel0);
            while texel0 > 0.0 && texel * 2.0 <= wanted * (1.0 + 1e-9) && (w > 1 || h > 1) {
                level += 1;
                w = w.div_ceil(2);
                h = h.div_ceil(2);
                texel *= 2.0;
            }
            plan.image = Some(shown);
            plan.size = size;
            plan.texel0 = texel0;
            plan.level = level;
            plan.level_size = (w, h);
            plan.texel = texel;
        }
        materials.push(plan);
    }
    Ok(Some(MeshPlan {
        file,
        materials,
        wanted,
        reason,
    }))
}

/// A textured mesh object ready to draw: the file's geometry (object frame, before scale and
/// pose), its texture coordinates and vertex colours, a material per triangle and each
/// material's [`Look`].
#[derive(Debug, Clone)]
pub struct Prepared {
    pub plan: MeshPlan,
    pub looks: Vec<Look>,
    /// Mip levels of each image look ([`super::mip`]) for the native renderer's footprint
    /// lookups; `None` for other looks and for images above [`MIP_MAX_TEXELS`].
    pub mips: Vec<Option<super::mip::Pyramid>>,
}

impl Prepared {
    pub fn mesh(&self) -> &TriMesh {
        &self.plan.file.mesh
    }

    /// Albedo of material `k` at texture coordinates `uv` and barycentric weights `w` of
    /// triangle `tri` (for vertex colours).
    pub fn albedo(&self, k: u32, uv: Option<[f64; 2]>, tri: u32, w: [f64; 3]) -> [f64; 3] {
        self.albedo_over(k, uv, tri, w, 0.0)
    }

    /// [`Prepared::albedo`] with an image averaged over a footprint `width` metres wide on
    /// the surface ([`super::mip::Pyramid::sample`], the material's mean texel size on the
    /// surface converting metres to texels); 0: a point lookup.
    pub fn albedo_over(
        &self,
        k: u32,
        uv: Option<[f64; 2]>,
        tri: u32,
        w: [f64; 3],
        width: f64,
    ) -> [f64; 3] {
        match self.looks.get(k as usize) {
            Some(Look::Color(c)) => *c,
            Some(Look::Image(img)) => match uv {
                Some([u, v]) => {
                    let texel = self.plan.materials.get(k as usize).map_or(0.0, |m| m.texel);
                    match self.mips.get(k as usize) {
                        Some(Some(p)) if texel > 0.0 && width > 0.0 => {
                            p.sample(u, v, width / texel, |u, v| img.sample(u, v))
                        }
                        _ => img.sample(u, v),
                    }
                }
                None => img.mean(),
            },
            Some(Look::VertexColors) => {
                let f = &self.plan.file;
                let t = f.mesh.triangles[tri as usize];
                let c = t.map(|i| f.colors[i as usize]);
                [0, 1, 2].map(|ch| {
                    w[0] * c[0][ch] as f64 + w[1] * c[1][ch] as f64 + w[2] * c[2][ch] as f64
                })
            }
            None => [0.0; 3],
        }
    }
}

/// The triangles of one material of a prepared mesh, with only the vertices they use: what
/// Mitsuba and Cycles receive, one file per material.
#[derive(Debug, Clone)]
pub struct Part {
    /// Index into [`Prepared::looks`].
    pub material: u32,
    /// Object frame, before scale and pose.
    pub mesh: TriMesh,
    /// Per vertex (empty when the file has none).
    pub uv: Vec<[f32; 2]>,
    /// Per vertex, linear (empty unless the look is vertex colours).
    pub colors: Vec<[f32; 3]>,
}

impl Prepared {
    /// One [`Part`] per material that has triangles, in material order.
    pub fn parts(&self) -> Vec<Part> {
        let f = &self.plan.file;
        let mut out = Vec::new();
        for k in 0..f.materials.len() as u32 {
            let mut remap: HashMap<u32, u32> = HashMap::new();
            let mut part = Part {
                material: k,
                mesh: TriMesh::default(),
                uv: Vec::new(),
                colors: Vec::new(),
            };
            let colors = matches!(self.looks.get(k as usize), Some(Look::VertexColors))
                && !f.colors.is_empty();
            for (t, _) in f
                .mesh
                .triangles
                .iter()
                .zip(&f.material)
                .filter(|(_, m)| **m == k)
            {
                let tri = t.map(|i| {
                    *remap.entry(i).or_insert_with(|| {
                        part.mesh.positions.push(f.mesh.positions[i as usize]);
                        if !f.uv.is_empty() {
                            part.uv.push(f.uv[i as usize]);
                        }
                        if colors {
                            part.colors.push(f.colors[i as usize]);
                        }
                        part.mesh.positions.len() as u32 - 1
                    })
                });
                part.mesh.triangles.push(tri);
            }
            if !part.mesh.triangles.is_empty() {
                out.push(part);
            }
        }
        out
    }
}

type CacheMap = HashMap<u64, Weak<Prepared>>;
static CACHE: Mutex<Option<CacheMap>> = Mutex::new(None);

/// Object `index` prepared (`None` when it is not a textured mesh): its images decoded, the
/// chosen levels made and the colour factors applied. Cached by content while any user holds
/// it.
pub fn prepare_object(model: &Model, index: usize) -> Result<Option<Arc<Prepared>>, String> {
    let o = &model.objects[index];
    if mesh_path(o, Path::new(".")).is_none() {
        return Ok(None);
    }
    // The level depends on the object, its file and the cameras and poses: the whole model.
    let json = serde_json::to_string(model).map_err(|e| e.to_string())?;
    let key = super::name_hash(&json) ^ crate::noise::mix64(index as u64);
    {
        let mut g = CACHE.lock().unwrap_or_else(|e| e.into_inner());
        let map = g.get_or_insert_with(HashMap::new);
        map.retain(|_, w| w.strong_count() > 0);
        if let Some(p) = map.get(&key).and_then(Weak::upgrade) {
            return Ok(Some(p));
        }
    }
    // The images the file's first lines name are decoded while its faces are parsed (a
    // prefetch: what it misses is decoded below, the same way).
    let (plan, mut early) = rayon::join(|| plan_object(model, index), || prefetch(model, index));
    let Some(plan) = plan? else {
        return Ok(None);
    };
    let err = |e: String| format!("object `{}`: {e}", o.name);
    let mut decoded: HashMap<(String, u32, [u64; 3], u8), Arc<Image16>> = HashMap::new();
    let mut looks = Vec::new();
    for (m, p) in plan.file.materials.iter().zip(&plan.materials) {
        looks.push(look(m, p, o.material.albedo, &mut decoded, &mut early).map_err(err)?);
    }
    let mips = looks.iter().map(pyramid).collect();
    let p = Arc::new(Prepared { plan, looks, mips });
    let mut g = CACHE.lock().unwrap_or_else(|e| e.into_inner());
    g.get_or_insert_with(HashMap::new)
        .insert(key, Arc::downgrade(&p));
    Ok(Some(p))
}

/// Images decoded ahead ([`prefetch`]): file, wrap, the image until it is taken.
type Early = Vec<(PathBuf, Wrap, Option<Image16>)>;

/// The images an OBJ object's first lines name, decoded
/// ([`crate::geometry::meshfile::obj_images_early`]); one that fails is left to the load to
/// report.
fn prefetch(model: &Model, index: usize) -> Early {
    let (base, roots) = roots(model);
    let Some(path) = mesh_path(&model.objects[index], &base) else {
        return Vec::new();
    };
    if crate::geometry::meshfile::Format::of(&path) != Some(crate::geometry::meshfile::Format::Obj)
    {
        return Vec::new();
    }
    crate::geometry::meshfile::obj_images_early(&path, &roots)
        .into_iter()
        .map(|(p, wrap)| {
            let image = crate::geometry::meshfile::read(&p)
                .and_then(|b| decode(&b, &p.display().to_string(), wrap))
                .ok();
            (p, wrap, image)
        })
        .collect()
}

/// Largest image (texels) given mip levels: the levels cost 4 bytes per texel of the image
/// (f32 RGB and coverage, a quarter of the texels at level 1 and [`MIP_MAX_LEVEL`] levels); a
/// larger image keeps point lookups.
pub const MIP_MAX_TEXELS: u64 = 1 << 24;
/// Deepest mip level of a mesh file's image: its texture atlas's charts have a padding the file
/// does not state, so the filter stays within a few texels (4-texel boxes).
pub const MIP_MAX_LEVEL: u32 = 2;

/// The mip levels of an image look (`None` for other looks and too large images).
fn pyramid(l: &Look) -> Option<super::mip::Pyramid> {
    let Look::Image(img) = l else {
        return None;
    };
    if img.width as u64 * img.height as u64 > MIP_MAX_TEXELS {
        return None;
    }
    let w = img.width as usize;
    Some(super::mip::Pyramid::build(
        img.width,
        img.height,
        img.wrap,
        MIP_MAX_LEVEL,
        |i, j| {
            let k = 3 * (j * w + i);
            ([0, 1, 2].map(|c| img.rgb[k + c] as f64 / 65535.0), 1.0)
        },
    ))
}

/// The look of one material: its image at the planned level times its colour, its vertex
/// colours, or its colour (the object's albedo when the file gives none).
fn look(
    m: &FileMaterial,
    p: &MaterialPlan,
    albedo: [f64; 3],
    decoded: &mut HashMap<(String, u32, [u64; 3], u8), Arc<Image16>>,
    early: &mut Early,
) -> Result<Look, String> {
    if m.vertex_colors {
        return Ok(Look::VertexColors);
    }
    let Some(img) = &m.image else {
        return Ok(Look::Color(m.color.unwrap_or(albedo)));
    };
    let factor = m.color.unwrap_or([1.0; 3]);
    let shown = img.shown();
    let key = (
        shown.clone(),
        p.level,
        factor.map(f64::to_bits),
        m.wrap as u8,
    );
    if let Some(i) = decoded.get(&key) {
        return Ok(Look::Image(i.clone()));
    }
    let prefetched = match &img.source {
        ImageSource::File(path) => early
            .iter_mut()
            .find(|(p, w, _)| p == path && *w == m.wrap)
            .and_then(|(_, _, i)| i.take()),
        ImageSource::Bytes(_) => None,
    };
    let mut image = match prefetched {
        Some(image) => image,
        None => {
            let bytes = match &img.source {
                ImageSource::File(path) => crate::geometry::meshfile::read(path)?,
                ImageSource::Bytes(b) => b.to_vec(),
            };
            decode(&bytes, &shown, m.wrap)?
        }
    };
    for _ in 0..p.level {
        image = image.half();
    }
    if factor != [1.0; 3] {
        for px in image.rgb.chunks_exact_mut(3) {
            for c in 0..3 {
                px[c] = (px[c] as f64 * factor[c]).round().clamp(0.0, 65535.0) as u16;
            }
        }
    }
    let image = Arc::new(image);
    decoded.insert(key, image.clone());
    Ok(Look::Image(image))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn img(w: u32, h: u32, wrap: Wrap) -> Image16 {
        let rgb = (0..w * h)
            .flat_map(|k| [(k * 1000) as u16, 0, 65535])
            .collect();
        Image16 {
            width: w,
            height: h,
            rgb,
            wrap,
        }
    }

    #[test]
    fn sampling_wraps_as_the_material_says() {
        let t = img(2, 1, Wrap::Clamp);
        assert_eq!(t.sample(0.25, 0.5)[0], 0.0);
        assert_eq!(t.sample(0.75, 0.5)[0], 1000.0 / 65535.0);
        assert_eq!(t.sample(0.0, 0.5)[0], 0.0);
        let r = img(2, 1, Wrap::Repeat);
        // At u = 0 the left texel blends half with the right one across the seam.
        assert!((r.sample(0.0, 0.5)[0] - 500.0 / 65535.0).abs() < 1e-12);
        assert_eq!(r.sample(1.25, 0.5), r.sample(0.25, 0.5));
        let m = img(2, 1, Wrap::Mirror);
        assert_eq!(m.sample(1.25, 0.5), m.sample(0.75, 0.5));
        assert_eq!(m.sample(0.0, 0.5)[0], 0.0);
    }

    #[test]
    fn halving_averages_in_linear_light() {
        let t = img(3, 2, Wrap::Clamp);
        let h = t.half();
        assert_eq!((h.width, h.height), (2, 1));
        // Texels 0, 1, 3, 4 → (0 + 1000 + 3000 + 4000) / 4.
        assert_eq!(h.rgb[0], 2000);
        // The odd column: 2, 2, 5, 5.
        assert_eq!(h.rgb[3], 3500);
        assert_eq!(h.rgb[2], 65535);
    }

    #[test]
    fn png_round_trips_sixteen_bits() {
        let t = img(5, 3, Wrap::Clamp);
        let png = t.png().unwrap();
        let back = image::load_from_memory(&png).unwrap().into_rgb16();
        assert_eq!(back.into_raw(), t.rgb);
    }

    #[test]
    fn srgb_images_are_decoded_to_linear() {
        let mut png = Vec::new();
        image::RgbImage::from_raw(2, 1, vec![0, 128, 255, 188, 188, 188])
            .unwrap()
            .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        let t = decode(&png, "t.png", Wrap::Clamp).unwrap();
        assert_eq!(t.rgb[0], 0);
        assert_eq!(t.rgb[2], 65535);
        // sRGB 128 → 0.2159; 188 → 0.5029.
        assert!((t.rgb[1] as f64 / 65535.0 - 0.21586).abs() < 1e-4);
        assert!((t.rgb[3] as f64 / 65535.0 - 0.50289).abs() < 1e-4);
    }

    /// A PNG whose header claims `w` × `h` pixels, with a little compressed pixel data (zeros:
    /// what a decompression bomb holds, 1000 to 1 or more).
    pub(crate) fn bomb_png(w: u32, h: u32) -> Vec<u8> {
        let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
        let mut chunk = |kind: &[u8], data: &[u8]| {
            out.extend_from_slice(&(data.len() as u32).to_be_bytes());
            let mut c = kind.to_vec();
            c.extend_from_slice(data);
            out.extend_from_slice(&c);
            out.extend_from_slice(&crc32(&c).to_be_bytes());
        };
        let mut ihdr = Vec::new();
        ihdr.extend_from_slice(&w.to_be_bytes());
        ihdr.extend_from_slice(&h.to_be_bytes());
        ihdr.extend_from_slice(&[8, 2, 0, 0, 0]);
        chunk(b"IHDR", &ihdr);
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
        std::io::Write::write_all(&mut z, &vec![0u8; 1 << 20]).unwrap();
        chunk(b"IDAT", &z.finish().unwrap());
        chunk(b"IEND", &[]);
        out
    }

    fn crc32(b: &[u8]) -> u32 {
        let mut c = 0xFFFF_FFFFu32;
        for &x in b {
            c ^= x as u32;
            for _ in 0..8 {
                c = if c & 1 != 0 {
                    0xEDB8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
            }
        }
        !c
    }

    #[test]
    fn a_decompression_bomb_is_refused_from_its_header() {
        let png = bomb_png(100_000, 100_000);
        let t0 = std::time::Instant::now();
        let e = decode(&png, "`bomb.png`", Wrap::Clamp).unwrap_err();
        assert!(e.contains("claims 100000×100000 pixels"), "{e}");
        assert!(t0.elapsed().as_secs_f64() < 1.0);
        let e = probe(b"not an image at all", "`x.png`").unwrap_err();
        assert!(e.contains("not a PNG, JPEG or OpenEXR"), "{e}");
    }
}

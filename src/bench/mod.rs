//! The benchmark harnesses behind `poser bench`: they drive the optics and the backends from
//! outside, so that no backend calls another and the optics stays pure math.
//!
//! | module | what |
//! |---|---|
//! | [`column`] | `poser bench column`: the solved water column against random walks through the water, on every shipped scene it applies to |
//! | [`evaluate`] | `poser bench evaluate`: CPU time and results of `poser evaluate` on the deformation lessons |
//! | [`images`] | `poser bench images`: COLMAP's whole pipeline on native renders of the shipped survey scenes |
//! | [`mesh`] | `poser bench mesh`: load, BVH, truth and a render of a generated 5 M-triangle textured site (OBJ + MTL + JPEG), with time and peak memory |
//! | [`parity`] | `poser bench parity`: every shipped scene in every backend, and whether they agree |
//! | [`projection`] | `poser bench projection`: port solvers (scalar, batch) against the double-double reference |
//! | [`render`] | `poser bench render`: speed against error of every render backend |
//! | [`sensor`] | `poser bench sensor`: the cost of an image at the camera's own noise, per daylight estimator |

pub mod column;
pub mod evaluate;
pub mod images;
pub mod mesh;
pub mod parity;
pub mod projection;
pub mod render;
pub mod sensor;

/// Run a `poser` child process (`what` names it in errors): its output and the CPU seconds it
/// took (user + system of the children, so no cache of this process helps it). A child that
/// fails is an error carrying its stderr.
pub(crate) fn run_child(
    cmd: &mut std::process::Command,
    what: &str,
) -> Result<(std::process::Output, f64), String> {
    let c0 = evaluate::cpu_seconds();
    let o = cmd
        .output()
        .map_err(|e| format!("cannot run {what}: {e}"))?;
    let cpu_s = evaluate::cpu_seconds() - c0;
    if !o.status.success() {
        return Err(format!(
            "{what} failed:\n{}",
            String::from_utf8_lossy(&o.stderr)
        ));
    }
    Ok((o, cpu_s))
}

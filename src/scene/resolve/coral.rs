//! Resolution of a `shape = "coral"` object's keys into [`Shape::Coral`] for `objects.rs`
//! (documented in [`crate::scene::format::Object`]; the mesh is [`crate::geometry::coral`]).
//!
//! | key | resolved to | check |
//! |---|---|---|
//! | `growth` | [`CoralGrowth`] | `branching` (default) or `massive` |
//! | `radius` | colony radius, m (default 0.3 m) | > 0, at most 10 m (`E0288`) |
//! | `seed` | the object's seed (given by the caller) | |

use crate::model::{CoralGrowth, Shape};
use crate::scene::check;
use crate::scene::diag::Diagnostic;
use crate::scene::format::types as F;
use crate::scene::reader::{Cx, Tab};
use crate::units::Dim;

/// The coral of object table `o`.
pub fn shape(cx: &mut Cx, o: &mut Tab, seed: u64) -> Shape {
    let growth = match o.choice(cx, F::Object::growth, &["branching", "massive"]) {
        Some("massive") => CoralGrowth::Massive,
        _ => CoralGrowth::Branching,
    };
    let radius = o.f64(cx, F::Object::radius, Dim::Length, 0.3);
    check::positive(cx, o, F::Object::radius, radius, "m");
    // The polygonising grid's cell is a fixed share of the radius: only absurd sizes need
    // refusing.
    let radius = if radius > 10.0 {
        cx.push(
            Diagnostic::error(
                "E0288",
                format!("`{}` is too large", o.full(F::Object::radius)),
            )
            .label(
                o.span_of(F::Object::radius),
                format!("{radius} m; at most 10 m"),
            )
            .help(
                "a coral colony is at most a few metres across; place several objects for a reef",
            ),
        );
        10.0
    } else {
        radius
    };
    Shape::Coral {
        growth,
        radius,
        seed,
    }
}

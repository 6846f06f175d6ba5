//! Positions as values (issue 16): a `Location` from `onLane` has `x`, `y`, `z` (m), `heading`
//! (rad) and `lane`; a position or velocity on a stream reaches a lambda as a [`Vector`] with
//! `x`, `y`, `z`. Differences, lengths (`abs`, `dist`) and `==` with a tolerance work between
//! them, so the paper's trigger `abs(c - start) < dist` and its `_ == target` run as written.
//!
//! Ground plane: a location is a point on the driving surface (`y` 0 on a road, the curb's
//! height on a sidewalk) while an actor's `pos` is its reference point above it (a car's
//! centre), so any difference that involves a location is taken in the ground plane (`x`,
//! `z`; its `y` is 0). Two vectors subtract in full 3-D.

use std::fmt;
use std::sync::{Arc, RwLock};

use allocative::Allocative;
use paracosm_engine::network::{Lane, Location};
use starlark::starlark_simple_value;
use starlark::values::float::StarlarkFloat;
use starlark::values::{
    starlark_value, Heap, NoSerialize, ProvidesStaticType, StarlarkValue, Value, ValueLike,
};
use starlark::StarlarkPagablePanic;

/// How close two positions must be to be `==`, in metres (in the ground plane when a location
/// is involved, in 3-D between two vectors): one micrometre, enough for the rounding of
/// coordinates computed two ways, far below any step an actor takes (a pedestrian at
/// 0.5 m/s moves 8 mm per step), so `pos == target` holds when an actor has arrived and not a
/// step before (the paper's `done = pos.filter(_ == target)`).
pub const POSITION_TOLERANCE_M: f64 = 1e-6;

/// The resolved locations of one evaluation of a program, by location index; shared by every
/// [`Loc`] value and updated by the scene builder when `connect` moves pieces.
pub type LocTable = Arc<RwLock<Vec<Option<Location>>>>;

/// A resolved `onLane(lane, at)`: a point of the road network.
#[derive(Debug, Clone, ProvidesStaticType, NoSerialize, StarlarkPagablePanic, Allocative)]
pub struct Loc {
    /// Index into the program's locations.
    pub index: usize,
    /// Where every location of the program stands now.
    #[allocative(skip)]
    pub table: LocTable,
}

impl Loc {
    /// Where it stands on the network as it is now; `None` before it is resolved.
    pub fn resolved(&self) -> Option<Location> {
        self.table
            .read()
            .ok()
            .and_then(|t| t.get(self.index).copied().flatten())
    }

    fn point(&self) -> starlark::Result<[f64; 3]> {
        self.resolved().map(|l| l.pos_m).ok_or_else(|| {
            starlark::Error::new_other(anyhow::anyhow!(
                "this location is not on the network (yet): its position is unknown"
            ))
        })
    }
}

impl fmt::Display for Loc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.resolved() {
            Some(l) => write!(
                f,
                "Location(x = {:.3}, y = {:.3}, z = {:.3}, heading = {:.4})",
                l.pos_m[0], l.pos_m[1], l.pos_m[2], l.heading_rad
            ),
            None => write!(f, "Location({})", self.index),
        }
    }
}

starlark_simple_value!(Loc);

const LOC_ATTRS: [&str; 5] = ["x", "y", "z", "heading", "lane"];

/// A point of either kind, and whether it is a location (a surface point).
fn as_point(v: Value) -> Option<([f64; 3], bool)> {
    if let Some(p) = v.downcast_ref::<Vector>() {
        return Some((p.0, false));
    }
    v.downcast_ref::<Loc>()
        .and_then(|l| l.resolved())
        .map(|l| (l.pos_m, true))
}

fn difference(a: [f64; 3], b: [f64; 3], ground: bool) -> [f64; 3] {
    [
        a[0] - b[0],
        if ground { 0.0 } else { a[1] - b[1] },
        a[2] - b[2],
    ]
}

fn positions_equal(me: [f64; 3], me_loc: bool, other: Value) -> starlark::Result<bool> {
    match as_point(other) {
        Some((p, loc)) => {
            let d = difference(me, p, me_loc || loc);
            Ok(norm(d) <= POSITION_TOLERANCE_M)
        }
        None => Err(starlark::Error::new_other(anyhow::anyhow!(
            "`==` compares a position with a position (a location or a vector), not with {}",
            crate::lang::a_type(other.get_type())
        ))),
    }
}

/// The Euclidean length of `v`.
pub fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

fn unsupported(op: &str, a: &str, b: Value) -> starlark::Error {
    starlark::Error::new_other(anyhow::anyhow!(
        "{a} {op} {} is not defined: positions add and subtract vectors and locations",
        b.get_type()
    ))
}

#[starlark_value(type = "Location")]
impl<'v> StarlarkValue<'v> for Loc {
    fn get_attr(&self, attribute: &str, heap: Heap<'v>) -> Option<Value<'v>> {
        let l = self.resolved()?;
        Some(match attribute {
            "x" => heap.alloc(l.pos_m[0]),
            "y" => heap.alloc(l.pos_m[1]),
            "z" => heap.alloc(l.pos_m[2]),
            "heading" => heap.alloc(l.heading_rad),
            "lane" => match l.lane {
                Lane::Driving(k) => heap.alloc(k),
                Lane::SideWalk => heap.alloc("SideWalk"),
                Lane::OppositeSideWalk => heap.alloc("-SideWalk"),
            },
            _ => return None,
        })
    }

    fn dir_attr(&self) -> Vec<String> {
        LOC_ATTRS.iter().map(|s| s.to_string()).collect()
    }

    fn equals(&self, other: Value<'v>) -> starlark::Result<bool> {
        positions_equal(self.point()?, true, other)
    }

    fn sub(&self, other: Value<'v>, heap: Heap<'v>) -> starlark::Result<Value<'v>> {
        match as_point(other) {
            Some((p, _)) => Ok(heap.alloc(Vector(difference(self.point()?, p, true)))),
            None => Err(unsupported("-", "Location", other)),
        }
    }
}

/// A 3-vector `(x, y, z)`: a position (m) or a velocity (m/s) carried by a stream, or a
/// difference of positions. It indexes and unpacks like a tuple of 3 numbers.
#[derive(Debug, Clone, Copy, ProvidesStaticType, NoSerialize, StarlarkPagablePanic, Allocative)]
pub struct Vector(pub [f64; 3]);

impl fmt::Display for Vector {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "Vector(x = {:.3}, y = {:.3}, z = {:.3})",
            self.0[0], self.0[1], self.0[2]
        )
    }
}

starlark_simple_value!(Vector);

/// A number (int or float) as `f64`.
pub fn num(v: Value) -> Option<f64> {
    if let Some(i) = v.unpack_i32() {
        return Some(f64::from(i));
    }
    v.downcast_ref::<StarlarkFloat>().map(|f| f.0)
}

#[starlark_value(type = "Vector")]
impl<'v> StarlarkValue<'v> for Vector {
    fn get_attr(&self, attribute: &str, heap: Heap<'v>) -> Option<Value<'v>> {
        let i = ["x", "y", "z"].iter().position(|a| *a == attribute)?;
        Some(heap.alloc(self.0[i]))
    }

    fn dir_attr(&self) -> Vec<String> {
        vec!["x".into(), "y".into(), "z".into()]
    }

    fn length(&self) -> starlark::Result<i32> {
        Ok(3)
    }

    fn at(&self, index: Value<'v>, heap: Heap<'v>) -> starlark::Result<Value<'v>> {
        match index.unpack_i32() {
            Some(i @ -3..=2) => Ok(heap.alloc(self.0[i.rem_euclid(3) as usize])),
            _ => Err(starlark::Error::new_other(anyhow::anyhow!(
                "a Vector has 3 items (x, y, z), index {index} is out of range"
            ))),
        }
    }

    fn iterate_collect(&self, heap: Heap<'v>) -> starlark::Result<Vec<Value<'v>>> {
        Ok(self.0.iter().map(|&x| heap.alloc(x)).collect())
    }

    fn equals(&self, other: Value<'v>) -> starlark::Result<bool> {
        positions_equal(self.0, false, other)
    }

    fn minus(&self, heap: Heap<'v>) -> starlark::Result<Value<'v>> {
        Ok(heap.alloc(Vector(self.0.map(|x| -x))))
    }

    fn add(&self, other: Value<'v>, heap: Heap<'v>) -> Option<starlark::Result<Value<'v>>> {
        let o = other.downcast_ref::<Vector>()?;
        Some(Ok(heap.alloc(Vector([
            self.0[0] + o.0[0],
            self.0[1] + o.0[1],
            self.0[2] + o.0[2],
        ]))))
    }

    fn sub(&self, other: Value<'v>, heap: Heap<'v>) -> starlark::Result<Value<'v>> {
        match as_point(other) {
            Some((p, loc)) => Ok(heap.alloc(Vector(difference(self.0, p, loc)))),
            None => Err(unsupported("-", "Vector", other)),
        }
    }

    fn mul(&self, other: Value<'v>, heap: Heap<'v>) -> Option<starlark::Result<Value<'v>>> {
        let k = num(other)?;
        Some(Ok(heap.alloc(Vector(self.0.map(|x| x * k)))))
    }

    fn rmul(&self, lhs: Value<'v>, heap: Heap<'v>) -> Option<starlark::Result<Value<'v>>> {
        self.mul(lhs, heap)
    }

    fn div(&self, other: Value<'v>, heap: Heap<'v>) -> starlark::Result<Value<'v>> {
        match num(other) {
            Some(k) if k != 0.0 => Ok(heap.alloc(Vector(self.0.map(|x| x / k)))),
            Some(_) => Err(starlark::Error::new_other(anyhow::anyhow!(
                "a Vector divided by zero"
            ))),
            None => Err(unsupported("/", "Vector", other)),
        }
    }
}

/// `abs(x)`: the absolute value of a number, the length of a [`Vector`] (m for a difference of
/// positions).
///
/// # Errors
/// Anything else.
pub fn abs_of<'v>(x: Value<'v>, heap: Heap<'v>) -> anyhow::Result<Value<'v>> {
    if let Some(i) = x.unpack_i32() {
        return Ok(heap.alloc(i.unsigned_abs()));
    }
    if let Some(f) = x.downcast_ref::<StarlarkFloat>() {
        return Ok(heap.alloc(f.0.abs()));
    }
    if let Some(v) = x.downcast_ref::<Vector>() {
        return Ok(heap.alloc(norm(v.0)));
    }
    if x.downcast_ref::<Loc>().is_some() {
        anyhow::bail!(
            "abs of a Location: subtract another position first, abs(a - b), or use dist(a, b)"
        );
    }
    anyhow::bail!(
        "abs takes a number or a Vector, got {}{}",
        crate::lang::a_type(x.get_type()),
        super::values::stream_hint(x)
    )
}

/// `dist(a, b)`: the distance between two positions in m (in the ground plane when either is
/// a location).
///
/// # Errors
/// An argument that is not a position.
pub fn dist_of(a: Value, b: Value) -> anyhow::Result<f64> {
    let point = |v: Value| {
        as_point(v).ok_or_else(|| {
            anyhow::anyhow!(
                "dist takes two positions (locations or vectors), got {}{}",
                crate::lang::a_type(v.get_type()),
                super::values::stream_hint(v)
            )
        })
    };
    let ((pa, la), (pb, lb)) = (point(a)?, point(b)?);
    Ok(norm(difference(pa, pb, la || lb)))
}

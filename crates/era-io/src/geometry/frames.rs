//! Coordinate systems: an origin and three orthonormal axes in the global frame, and
//! the Cartesian, cylindrical or spherical coordinates measured in them.

use serde::{Deserialize, Serialize};

/// How coordinates in a system are read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SystemKind {
    /// `(x, y, z)`; code 0.
    Cartesian,
    /// `(r, θ in degrees from x towards y, z)`; code 1.
    Cylindrical,
    /// `(r, θ in degrees from z, φ in degrees from x towards y)`; code 2.
    Spherical,
}

impl SystemKind {
    /// From the UFF code (0, 1, 2).
    pub fn from_code(code: i64) -> Option<Self> {
        Some(match code {
            0 => SystemKind::Cartesian,
            1 => SystemKind::Cylindrical,
            2 => SystemKind::Spherical,
            _ => return None,
        })
    }
    /// The UFF code.
    pub fn code(self) -> i64 {
        match self {
            SystemKind::Cartesian => 0,
            SystemKind::Cylindrical => 1,
            SystemKind::Spherical => 2,
        }
    }
}

/// A coordinate system in the global frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CoordinateSystem {
    /// Its number (nodes refer to it); never 0, the global frame.
    pub id: i64,
    /// Its name, possibly empty.
    #[serde(default)]
    pub name: String,
    /// How coordinates in it are read.
    pub kind: SystemKind,
    /// Its origin, global.
    pub origin: [f64; 3],
    /// Its x, y and z axes as global unit vectors (the rows of dataset 2420's matrix).
    pub axes: [[f64; 3]; 3],
}

pub(crate) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn scaled(a: [f64; 3], s: f64) -> [f64; 3] {
    a.map(|v| v * s)
}
fn unit(a: [f64; 3]) -> Option<[f64; 3]> {
    let n = dot(a, a).sqrt();
    (n.is_finite() && n > 1e-12).then(|| scaled(a, 1.0 / n))
}

impl CoordinateSystem {
    /// The system of dataset 18's method 1: an origin, a point on the +x axis and a
    /// point in the +xz plane, all global. `None` when the points do not span a plane.
    pub fn from_points(
        id: i64,
        name: String,
        kind: SystemKind,
        origin: [f64; 3],
        on_x: [f64; 3],
        in_xz: [f64; 3],
    ) -> Option<Self> {
        let x = unit(sub(on_x, origin))?;
        let v = sub(in_xz, origin);
        let normal = sub(v, scaled(x, dot(v, x)));
        // A +xz point (nearly) on the x axis leaves the plane undefined.
        if dot(normal, normal).sqrt() <= 1e-6 * dot(v, v).sqrt() {
            return None;
        }
        let z = unit(normal)?;
        let y = cross(z, x);
        Some(CoordinateSystem {
            id,
            name,
            kind,
            origin,
            axes: [x, y, z],
        })
    }

    /// Global position of a point given in this system's coordinates.
    pub fn to_global(&self, c: [f64; 3]) -> [f64; 3] {
        let local = match self.kind {
            SystemKind::Cartesian => c,
            SystemKind::Cylindrical => {
                let t = c[1].to_radians();
                [c[0] * t.cos(), c[0] * t.sin(), c[2]]
            }
            SystemKind::Spherical => {
                let (t, p) = (c[1].to_radians(), c[2].to_radians());
                [
                    c[0] * t.sin() * p.cos(),
                    c[0] * t.sin() * p.sin(),
                    c[0] * t.cos(),
                ]
            }
        };
        let mut g = self.origin;
        for (axis, l) in self.axes.iter().zip(local) {
            for (gi, ai) in g.iter_mut().zip(axis) {
                *gi += l * ai;
            }
        }
        g
    }

    /// The global unit vector of this system's direction `axis` (0, 1, 2) at the global
    /// point `at`: the axis itself for a Cartesian system; r̂, θ̂, ẑ (cylindrical) or
    /// r̂, θ̂, φ̂ (spherical) at that point otherwise. On the axis of a cylindrical or
    /// spherical system, where the angle is undefined, the angle 0 is used.
    pub fn direction_at(&self, at: [f64; 3], axis: usize) -> [f64; 3] {
        let d = sub(at, self.origin);
        let l = [
            dot(d, self.axes[0]),
            dot(d, self.axes[1]),
            dot(d, self.axes[2]),
        ];
        let local = match self.kind {
            SystemKind::Cartesian => {
                let mut e = [0.0; 3];
                e[axis] = 1.0;
                e
            }
            SystemKind::Cylindrical => {
                let t = l[1].atan2(l[0]);
                match axis {
                    0 => [t.cos(), t.sin(), 0.0],
                    1 => [-t.sin(), t.cos(), 0.0],
                    _ => [0.0, 0.0, 1.0],
                }
            }
            SystemKind::Spherical => {
                let p = l[1].atan2(l[0]);
                let t = (l[0].hypot(l[1])).atan2(l[2]);
                match axis {
                    0 => [t.sin() * p.cos(), t.sin() * p.sin(), t.cos()],
                    1 => [t.cos() * p.cos(), t.cos() * p.sin(), -t.sin()],
                    _ => [-p.sin(), p.cos(), 0.0],
                }
            }
        };
        let mut g = [0.0; 3];
        for (axis, v) in self.axes.iter().zip(local) {
            for (gi, ai) in g.iter_mut().zip(axis) {
                *gi += v * ai;
            }
        }
        g
    }

    /// Finite origin and orthonormal, right-handed axes (to 1e-4).
    pub(crate) fn check(&self) -> Result<(), String> {
        let finite = self.origin.iter().chain(self.axes.iter().flatten());
        if finite.clone().any(|v| !v.is_finite()) {
            return Err(format!(
                "coordinate system {}: a value is not a finite number",
                self.id
            ));
        }
        const TOL: f64 = 1e-4;
        for i in 0..3 {
            for j in 0..3 {
                let want = if i == j { 1.0 } else { 0.0 };
                let got = dot(self.axes[i], self.axes[j]);
                if (got - want).abs() > TOL {
                    return Err(format!(
                        "coordinate system {}: its axes are not orthonormal (row {} · row {} = {got:.6})",
                        self.id,
                        i + 1,
                        j + 1
                    ));
                }
            }
        }
        if dot(cross(self.axes[0], self.axes[1]), self.axes[2]) < 0.0 {
            return Err(format!(
                "coordinate system {}: its axes are left-handed",
                self.id
            ));
        }
        Ok(())
    }
}

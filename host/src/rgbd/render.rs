//! A small ray caster for `gen-rgbd`: unions of solids given by signed
//! distance functions, sphere-traced from a pin-hole camera looking at a
//! turntable, with Lambert and Blinn shading, procedural textures, a 16-bit
//! depth map and the object mask.

/// A 3-vector.
pub type V3 = [f64; 3];

fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn mul(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn len(a: V3) -> f64 {
    dot(a, a).sqrt()
}
fn norm(a: V3) -> V3 {
    mul(a, 1.0 / len(a).max(1e-12))
}
fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Rotation about the x axis (rad), as rows.
pub fn rot_x(a: f64) -> [V3; 3] {
    let (s, c) = a.sin_cos();
    [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]
}

/// Rotation about the z axis (rad), as rows.
pub fn rot_z(a: f64) -> [V3; 3] {
    let (s, c) = a.sin_cos();
    [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
}

const IDENTITY: [V3; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// A solid in its own frame (y up), in metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Solid {
    /// Radius.
    Sphere(f64),
    /// Half extents.
    Box(V3),
    /// Radius, half height (axis y).
    Cylinder(f64, f64),
    /// Base radius at `y = −h`, top radius at `y = +h`, half height `h`.
    Cone(f64, f64, f64),
    /// Major radius (in the xz plane), minor radius.
    Torus(f64, f64),
    /// Semi-axes and the two exponents `(ε1, ε2)` (1 = ellipsoid,
    /// small = boxy).
    Superquadric(V3, f64, f64),
}

/// Surface pattern.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Texture {
    /// One colour.
    Plain,
    /// Horizontal bands.
    Stripes,
    /// A 3-D checkerboard.
    Checker,
    /// Speckled noise.
    Speckle,
}

/// A solid placed in the object frame, with its material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Part {
    /// The solid.
    pub solid: Solid,
    /// Position of its centre.
    pub at: V3,
    /// Rotation, object frame to solid frame (rows).
    pub rot: [V3; 3],
    /// Linear RGB albedo.
    pub colour: V3,
    /// Second colour of the pattern.
    pub colour2: V3,
    /// Pattern.
    pub texture: Texture,
    /// Pattern frequency, 1/m.
    pub freq: f64,
}

impl Part {
    /// An upright solid at `at` in one colour.
    pub fn new(solid: Solid, at: V3, colour: V3) -> Self {
        Self {
            solid,
            at,
            rot: IDENTITY,
            colour,
            colour2: colour,
            texture: Texture::Plain,
            freq: 40.0,
        }
    }

    fn local(&self, p: V3) -> V3 {
        let q = sub(p, self.at);
        [
            dot(self.rot[0], q),
            dot(self.rot[1], q),
            dot(self.rot[2], q),
        ]
    }

    fn sdf(&self, p: V3) -> f64 {
        let q = self.local(p);
        match self.solid {
            Solid::Sphere(r) => len(q) - r,
            Solid::Box(b) => {
                let d = [q[0].abs() - b[0], q[1].abs() - b[1], q[2].abs() - b[2]];
                let out = len([d[0].max(0.0), d[1].max(0.0), d[2].max(0.0)]);
                out + d[0].max(d[1]).max(d[2]).min(0.0)
            }
            Solid::Cylinder(r, h) => {
                let d = [q[0].hypot(q[2]) - r, q[1].abs() - h];
                d[0].max(d[1]).min(0.0) + d[0].max(0.0).hypot(d[1].max(0.0))
            }
            Solid::Cone(r1, r2, h) => {
                // Inigo Quilez's capped cone.
                let qx = q[0].hypot(q[2]);
                let qy = q[1];
                let k1 = [r2, h];
                let k2 = [r2 - r1, 2.0 * h];
                let r = if qy < 0.0 { r1 } else { r2 };
                let ca = [qx - qx.min(r), qy.abs() - h];
                let t = (((k1[0] - qx) * k2[0] + (k1[1] - qy) * k2[1])
                    / (k2[0] * k2[0] + k2[1] * k2[1]))
                    .clamp(0.0, 1.0);
                let cb = [qx - k1[0] + k2[0] * t, qy - k1[1] + k2[1] * t];
                let s = if cb[0] < 0.0 && ca[1] < 0.0 {
                    -1.0
                } else {
                    1.0
                };
                s * (ca[0] * ca[0] + ca[1] * ca[1])
                    .min(cb[0] * cb[0] + cb[1] * cb[1])
                    .sqrt()
            }
            Solid::Torus(big, small) => (q[0].hypot(q[2]) - big).hypot(q[1]) - small,
            Solid::Superquadric(a, e1, e2) => {
                let f = |v: f64, s: f64, e: f64| (v / s).abs().powf(2.0 / e);
                let xz = (f(q[0], a[0], e2) + f(q[2], a[2], e2)).powf(e2 / e1);
                let g = (xz + f(q[1], a[1], e1)).powf(e1 / 2.0);
                // Inside-outside function scaled to a distance (conservative
                // enough with the tracer's under-relaxation).
                (g - 1.0) * a[0].min(a[1]).min(a[2]) * 0.5
            }
        }
    }

    fn albedo(&self, p: V3) -> V3 {
        let q = self.local(p);
        let k = self.freq;
        let second = match self.texture {
            Texture::Plain => false,
            Texture::Stripes => (q[1] * k).sin() > 0.0,
            Texture::Checker => {
                ((q[0] * k).floor() + (q[1] * k).floor() + (q[2] * k).floor()) as i64 % 2 == 0
            }
            Texture::Speckle => hash3(q, k) > 0.7,
        };
        if second {
            self.colour2
        } else {
            self.colour
        }
    }
}

fn hash3(q: V3, k: f64) -> f64 {
    let c = [
        (q[0] * k * 3.0).floor(),
        (q[1] * k * 3.0).floor(),
        (q[2] * k * 3.0).floor(),
    ];
    let h = (c[0] * 127.1 + c[1] * 311.7 + c[2] * 74.7).sin() * 43_758.545_3;
    h - h.floor()
}

/// A union of parts, resting on the turntable at `y = 0`.
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    /// Its parts.
    pub parts: Vec<Part>,
    /// Radius of a sphere about `(0, centre_y, 0)` that holds it.
    pub radius: f64,
    /// Height of that sphere's centre.
    pub centre_y: f64,
}

impl Object {
    fn sdf(&self, p: V3) -> (f64, usize) {
        let mut best = (f64::INFINITY, 0);
        for (i, part) in self.parts.iter().enumerate() {
            let d = part.sdf(p);
            if d < best.0 {
                best = (d, i);
            }
        }
        best
    }
}

/// The camera of one view: the turntable angle and the elevation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// Turntable angle, rad.
    pub azimuth: f64,
    /// Camera elevation above the horizon, rad.
    pub elevation: f64,
    /// Distance from the camera to the object's centre, m.
    pub distance: f64,
    /// Focal length, px (the Kinect's is about 570 at 640×480).
    pub focal: f64,
}

/// One rendered window: linear RGB, z-depth in m (0 = no return), mask.
#[derive(Clone, Debug, PartialEq)]
pub struct Render {
    /// Width and height, px.
    pub size: usize,
    /// Row-major linear RGB.
    pub rgb: Vec<V3>,
    /// Row-major z-depth, m; 0 where the ray hits nothing.
    pub depth: Vec<f64>,
    /// Row-major cosine between the surface normal and the view ray.
    pub facing: Vec<f64>,
    /// Row-major object mask.
    pub mask: Vec<bool>,
    /// Window's top-left corner in a 640×480 frame.
    pub origin: (i64, i64),
}

/// Renders a square window about the object, sized to its bounding sphere.
pub fn render(obj: &Object, view: &View, table: V3) -> Render {
    // The object turns: rotating the world by −azimuth about y is the same
    // as moving the camera around it.
    let (sa, ca) = view.azimuth.sin_cos();
    let (se, ce) = view.elevation.sin_cos();
    let target = [0.0, obj.centre_y, 0.0];
    let eye = add(target, mul([ce * sa, se, ce * ca], view.distance));
    let fwd = norm(sub(target, eye));
    let right = norm(cross(fwd, [0.0, 1.0, 0.0]));
    let up = cross(right, fwd);
    let half = (1.2 * view.focal * obj.radius / view.distance)
        .ceil()
        .max(4.0);
    let size = 2 * half as usize;
    let light = norm([-0.4, 0.8, 0.45]);
    let mut out = Render {
        size,
        rgb: vec![[0.0; 3]; size * size],
        depth: vec![0.0; size * size],
        facing: vec![0.0; size * size],
        mask: vec![false; size * size],
        origin: (320 - half as i64, 240 - half as i64),
    };
    for y in 0..size {
        for x in 0..size {
            let u = (x as f64 + 0.5 - half) / view.focal;
            let v = (half - y as f64 - 0.5) / view.focal;
            let dir = norm(add(fwd, add(mul(right, u), mul(up, v))));
            let i = y * size + x;
            let (t, hit) = trace(obj, eye, dir, view.distance, obj.radius);
            let (t, n, albedo, is_obj) = if let Some(part) = hit {
                let p = add(eye, mul(dir, t));
                let n = normal(obj, p);
                (t, n, obj.parts[part].albedo(p), true)
            } else if dir[1] < -1e-6 {
                let t = -eye[1] / dir[1];
                let p = add(eye, mul(dir, t));
                let ring = (p[0].hypot(p[2]) * 30.0).floor() as i64 % 2 == 0;
                let shade = if ring { 1.0 } else { 0.9 };
                (t, [0.0, 1.0, 0.0], mul(table, shade), false)
            } else {
                out.rgb[i] = [0.05, 0.05, 0.06];
                continue;
            };
            let p = add(eye, mul(dir, t));
            let lit = shadowed(obj, p, light, is_obj);
            let diffuse = dot(n, light).max(0.0) * lit;
            let h = norm(sub(light, dir));
            let spec = if is_obj {
                0.25 * dot(n, h).max(0.0).powi(24) * lit
            } else {
                0.0
            };
            out.rgb[i] = [0, 1, 2].map(|c| albedo[c] * (0.25 + 0.8 * diffuse) + spec);
            out.depth[i] = t * dot(dir, fwd);
            out.facing[i] = -dot(n, dir);
            out.mask[i] = is_obj;
        }
    }
    out
}

/// Sphere tracing inside the bounding sphere: `(t, Some(part))` on a hit.
fn trace(obj: &Object, eye: V3, dir: V3, dist: f64, radius: f64) -> (f64, Option<usize>) {
    let mut t = (dist - radius * 1.05).max(0.0);
    let far = dist + radius * 1.05;
    for _ in 0..160 {
        let (d, part) = obj.sdf(add(eye, mul(dir, t)));
        if d < 2e-4 {
            return (t, Some(part));
        }
        t += d * 0.8;
        if t > far {
            break;
        }
    }
    (t, None)
}

fn normal(obj: &Object, p: V3) -> V3 {
    let e = 1e-4;
    let f = |q: V3| obj.sdf(q).0;
    norm([
        f(add(p, [e, 0.0, 0.0])) - f(sub(p, [e, 0.0, 0.0])),
        f(add(p, [0.0, e, 0.0])) - f(sub(p, [0.0, e, 0.0])),
        f(add(p, [0.0, 0.0, e])) - f(sub(p, [0.0, 0.0, e])),
    ])
}

/// 1 when `p` sees the light, 0.35 in the object's shadow.
fn shadowed(obj: &Object, p: V3, light: V3, on_object: bool) -> f64 {
    let mut t = if on_object { 2e-3 } else { 1e-3 };
    for _ in 0..64 {
        let (d, _) = obj.sdf(add(p, mul(light, t)));
        if d < 1e-4 {
            return 0.35;
        }
        t += d.max(1e-3);
        if t > 2.0 * obj.radius + 0.5 {
            break;
        }
    }
    1.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances_of_the_solids() {
        let at = |s| Part::new(s, [0.0; 3], [1.0; 3]);
        let p = [0.0, 0.0, 0.3];
        assert!((at(Solid::Sphere(0.1)).sdf(p) - 0.2).abs() < 1e-12);
        assert!((at(Solid::Box([0.1; 3])).sdf(p) - 0.2).abs() < 1e-12);
        assert!((at(Solid::Cylinder(0.1, 0.2)).sdf(p) - 0.2).abs() < 1e-12);
        assert!((at(Solid::Torus(0.2, 0.05)).sdf(p) - 0.05).abs() < 1e-12);
        assert!(at(Solid::Cone(0.1, 0.0, 0.1)).sdf([0.0, 0.0, 0.0]) < 0.0);
        let sq = at(Solid::Superquadric([0.1; 3], 1.0, 1.0));
        assert!(sq.sdf([0.0; 3]) < 0.0 && sq.sdf(p) > 0.0);
    }

    #[test]
    fn a_sphere_renders_round_with_depth_inside_its_mask() {
        let obj = Object {
            parts: vec![Part::new(Solid::Sphere(0.1), [0.0, 0.1, 0.0], [0.8; 3])],
            radius: 0.1,
            centre_y: 0.1,
        };
        let view = View {
            azimuth: 0.3,
            elevation: 0.6,
            distance: 1.0,
            focal: 300.0,
        };
        let r = render(&obj, &view, [0.5; 3]);
        let area = r.mask.iter().filter(|&&m| m).count() as f64;
        let expected = std::f64::consts::PI * (300.0 * 0.1f64).powi(2);
        assert!((area / expected - 1.0).abs() < 0.1, "{area} vs {expected}");
        let c = r.size / 2 * r.size + r.size / 2;
        assert!(
            r.mask[c] && (r.depth[c] - 0.9).abs() < 0.01,
            "{}",
            r.depth[c]
        );
    }
}

//! The geometry of the six cube-map frusta around one eye (Widmer et al. 2015, §5.4: "we
//! begin by determining the frustum (cube face) the ray originates from ... if no valid hit
//! was found, we transition to a new face based on which of the frustum planes of the
//! current view the ray hits. If the ray hits the far plane of any view ... we terminate").
//!
//! Face `i` (order +X, -X, +Y, -Y, +Z, -Z, [`CubeMap::face_camera`]) is the 90° frustum of
//! its pinhole between view depths `near` and `far`, the same for all six faces, so the
//! frusta tile the shell between the **near cube** and the **far cube** (the axis-aligned
//! cubes of half-size `near` and `far` around the eye) without gaps or overlap. In the
//! face's camera coordinates `q` (view depth `d = -q.z`) the frustum is
//! `|q.x| <= d`, `|q.y| <= d`, `near <= d <= far`; a ray leaves it through
//!
//! - a **side plane** (`q.x = ±d` or `q.y = ±d`): the plane through the eye and the cube
//!   edge shared with the neighbour whose axis is `±right` or `±up` of this face, where it
//!   continues ([`neighbour`]);
//! - the **far plane**: it leaves the captured scene (a miss);
//! - the **near plane**: it enters the near cube, which holds nothing (the near plane lies
//!   in front of every captured depth), and continues in the face through whose near plane
//!   it leaves that cube.
//!
//! [`FaceWalk`] yields the faces a ray visits in order; a line meets each convex frustum in
//! one interval, so it visits at most six (plus passes through the near cube), and the walk
//! is cut after [`MAX_FACE_VISITS`].

use glam::{Mat3, Vec3};
use parallax_core::Ray;
use parallax_scene::camera::CubeMap;

/// Most faces a walk visits (six frusta and two near-cube passes, with slack).
pub const MAX_FACE_VISITS: u32 = 12;

/// The exit of a ray from one face's frustum.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Exit {
    /// Through a side plane into this face.
    Side(usize),
    Far,
    Near,
}

/// The per-face frames and the shared depth range of a cube map.
#[derive(Clone, Debug)]
pub struct Faces {
    pub eye: Vec3,
    pub near: f32,
    pub far: f32,
    /// World -> face camera rotation per face.
    to_camera: [Mat3; 6],
    /// Neighbour across `+x, -x, +y, -y` of the face camera, per face.
    neighbours: [[usize; 4]; 6],
}

/// The face whose axis is `±` the given world direction (a face camera's right or up).
pub fn neighbour(axis: Vec3) -> usize {
    CubeMap::face_of(axis)
}

impl Faces {
    /// The faces of `cube` between view depths `near < far`.
    pub fn new(cube: &CubeMap, near: f32, far: f32) -> Self {
        let mut to_camera = [Mat3::IDENTITY; 6];
        let mut neighbours = [[0; 4]; 6];
        for (i, (t, n)) in to_camera.iter_mut().zip(&mut neighbours).enumerate() {
            let b = cube.face_camera(i).frame.basis;
            *t = b.transpose();
            let (right, up) = (b.x_axis, b.y_axis);
            *n = [
                neighbour(right),
                neighbour(-right),
                neighbour(up),
                neighbour(-up),
            ];
        }
        Self {
            eye: cube.eye,
            near,
            far,
            to_camera,
            neighbours,
        }
    }

    /// The face of the point `p` (dominant axis of `p - eye`, ties to the first face).
    #[inline]
    pub fn face_at(&self, p: Vec3) -> usize {
        CubeMap::face_of(p - self.eye)
    }

    /// Max-norm distance of `p` from the eye.
    #[inline]
    fn cube_radius(&self, p: Vec3) -> f32 {
        (p - self.eye).abs().max_element()
    }

    /// The parameters `(enter, leave)` of `ray` in the axis-aligned cube of half-size `h`
    /// around the eye from `t` on (slab test; `enter = t` when it starts inside), `None` when
    /// it does not meet the cube after `t`.
    fn in_cube(&self, ray: &Ray, h: f32, t: f32) -> Option<(f32, f32)> {
        let o = ray.origin - self.eye;
        let (mut lo, mut hi) = (t, f32::INFINITY);
        for a in 0..3 {
            let (oa, da) = (o[a], ray.dir[a]);
            if da == 0.0 {
                if oa.abs() > h {
                    return None;
                }
                continue;
            }
            let (t0, t1) = ((-h - oa) / da, (h - oa) / da);
            let (t0, t1) = if t0 < t1 { (t0, t1) } else { (t1, t0) };
            lo = lo.max(t0);
            hi = hi.min(t1);
        }
        (lo <= hi).then_some((lo, hi))
    }

    /// The ray parameter where `ray` leaves the cube of half-size `h` after `t`.
    fn leave_cube(&self, ray: &Ray, h: f32, t: f32) -> Option<f32> {
        self.in_cube(ray, h, t).map(|(_, hi)| hi)
    }

    /// The ray parameter where `ray` enters the far cube (`t` itself when it starts inside),
    /// `None` when it never does after `t`.
    fn enter_far(&self, ray: &Ray, t: f32) -> Option<f32> {
        self.in_cube(ray, self.far, t).map(|(lo, _)| lo)
    }

    /// Where `ray`, at parameter `t` inside face `face`'s frustum (or on its boundary),
    /// leaves it: the parameter and the plane (module docs). Each frustum plane is
    /// `alpha + beta t >= 0` in the face's camera coordinates; the exit is the smallest root
    /// `-alpha / beta` of a plane with `beta < 0` not before `t` (ties: side planes in the
    /// order `+x, -x, +y, -y`, then far, then near).
    pub fn exit(&self, face: usize, ray: &Ray, t: f32) -> (f32, Exit) {
        let r = &self.to_camera[face];
        let q0 = *r * (ray.origin - self.eye);
        let qd = *r * ray.dir;
        // d = -q.z.
        let (d0, dd) = (-q0.z, -qd.z);
        let planes = [
            (d0 - q0.x, dd - qd.x, Exit::Side(self.neighbours[face][0])),
            (d0 + q0.x, dd + qd.x, Exit::Side(self.neighbours[face][1])),
            (d0 - q0.y, dd - qd.y, Exit::Side(self.neighbours[face][2])),
            (d0 + q0.y, dd + qd.y, Exit::Side(self.neighbours[face][3])),
            (self.far - d0, -dd, Exit::Far),
            (d0 - self.near, dd, Exit::Near),
        ];
        let mut best = (f32::INFINITY, Exit::Far);
        for (alpha, beta, exit) in planes {
            if beta < 0.0 {
                let root = (-alpha / beta).max(t);
                if root < best.0 {
                    best = (root, exit);
                }
            }
        }
        best
    }

    /// The faces `ray` visits from `ray.t_min` on, in order ([`FaceWalk`]).
    pub fn walk<'a>(&'a self, ray: &'a Ray) -> FaceWalk<'a> {
        FaceWalk {
            faces: self,
            ray,
            next: None,
            t: ray.t_min.max(0.0),
            visits: 0,
            started: false,
            done: false,
            truncated: false,
        }
    }

    /// The face the walk continues in from parameter `t` outside every frustum's interior
    /// side (inside the near cube or beyond the far cube): through the near cube to the face
    /// it leaves it by, or into the far cube. `None`: the ray never reaches a frustum again.
    fn resume(&self, ray: &Ray, t: f32) -> Option<(usize, f32)> {
        let p = ray.at(t);
        let r = self.cube_radius(p);
        let t = if r > self.far {
            self.enter_far(ray, t)?
        } else if r < self.near {
            self.leave_cube(ray, self.near, t)?
        } else {
            t
        };
        let p = ray.at(t);
        (self.cube_radius(p) <= self.far * (1.0 + 1e-6)).then(|| (self.face_at(p), t))
    }

    /// The face where `ray`, entering the near cube at `t`, leaves it (`None`: it ends inside
    /// or the exit lies beyond the far cube).
    fn cross_near_cube(&self, ray: &Ray, t: f32) -> Option<(usize, f32)> {
        let t = self.leave_cube(ray, self.near, t)?;
        let p = ray.at(t);
        (self.cube_radius(p) <= self.far * (1.0 + 1e-6)).then(|| (self.face_at(p), t))
    }
}

/// The faces a ray visits, in order along the ray ([`Faces::walk`]): each item is a face
/// and the ray parameter where the ray enters it.
pub struct FaceWalk<'a> {
    faces: &'a Faces,
    ray: &'a Ray,
    next: Option<(usize, f32)>,
    t: f32,
    visits: u32,
    started: bool,
    done: bool,
    /// The walk was cut after [`MAX_FACE_VISITS`].
    pub truncated: bool,
}

impl Iterator for FaceWalk<'_> {
    type Item = (usize, f32);

    fn next(&mut self) -> Option<(usize, f32)> {
        if self.done {
            return None;
        }
        let f = self.faces;
        let cur = if !self.started {
            self.started = true;
            f.resume(self.ray, self.t)
        } else {
            self.next.take()
        };
        let Some((face, t)) = cur else {
            self.done = true;
            return None;
        };
        if !(t < self.ray.t_max) {
            self.done = true;
            return None;
        }
        self.visits += 1;
        if self.visits > MAX_FACE_VISITS {
            self.truncated = true;
            self.done = true;
            return None;
        }
        // Where the walk goes after this face; no next face makes this one the last.
        let (t_exit, exit) = f.exit(face, self.ray, t);
        self.next = match exit {
            Exit::Side(n) => Some((n, t_exit)),
            Exit::Far => None,
            // On the near plane the point is on the near cube's surface up to rounding: leave
            // the cube from there rather than asking which side of it the point lies on.
            Exit::Near => f.cross_near_cube(self.ray, t_exit),
        };
        self.done = self.next.is_none();
        Some((face, t))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use parallax_scene::CameraDesc;

    fn faces() -> Faces {
        let desc = CameraDesc::new(Vec3::new(0.5, 1.0, -0.25), Vec3::ZERO, Vec3::Y, 60.0);
        Faces::new(&CubeMap::new(&desc, 16).unwrap(), 0.1, 50.0)
    }

    #[test]
    fn neighbours_share_an_edge() {
        let f = faces();
        for face in 0..6 {
            let axis = parallax_scene::camera::cube::FACE_AXES[face];
            for &n in &f.neighbours[face] {
                let other = parallax_scene::camera::cube::FACE_AXES[n];
                assert_eq!(axis.dot(other), 0.0, "{face} -> {n}");
            }
        }
    }

    #[test]
    fn a_ray_from_the_eye_visits_one_face() {
        let f = faces();
        let ray = Ray::new(f.eye, Vec3::new(0.2, 0.1, -1.0).normalize());
        let v: Vec<_> = f.walk(&ray).collect();
        assert_eq!(v.len(), 1);
        assert_eq!(v[0].0, 5);
    }

    #[test]
    fn a_sideways_ray_crosses_into_the_neighbour() {
        let f = faces();
        // From a point in front of the eye (-Z face) heading +X: into the +X face.
        let ray = Ray::new(f.eye + Vec3::new(0.0, 0.0, -2.0), Vec3::X);
        let v: Vec<_> = f.walk(&ray).collect();
        assert_eq!(v.iter().map(|x| x.0).collect::<Vec<_>>(), vec![5, 0]);
        // The transition is where x - eye.x = 2 (the plane x = -z through the eye).
        assert!((v[1].1 - 2.0).abs() < 1e-5, "{v:?}");
        // A ray passing through the near cube: -X face, near cube, +X face.
        let ray = Ray::new(f.eye + Vec3::new(-1.0, 0.01, 0.02), Vec3::X);
        let v: Vec<_> = f.walk(&ray).map(|x| x.0).collect();
        assert_eq!(v, vec![1, 0]);
    }
}

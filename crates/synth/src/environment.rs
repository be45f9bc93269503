//! The environment of a colour + depth input: the pixels without depth (sky, an open window)
//! are background at infinity, so a ray that misses every layer takes their colour **by
//! direction** instead of one flat background colour.
//!
//! Widmer et al. 2015 (§5.1) warp rendered references whose misses take the scene's
//! environment colour; a user's colour + depth pair has no scene, only the colour its camera
//! saw in the directions where the depth holds no surface. [`Environment`] keeps those colours
//! as a direction map in the reference camera: a direction is projected into the reference
//! film ([`Pinhole::film_of_camera_point`] of the direction) and the colour is blended
//! bilinearly from the 2x2 pixel centres around it. So that every direction has a colour,
//! the pixels that hold a surface (and directions outside the film, clamped to its border)
//! take the colour of the nearest sky pixel (multi-source breadth-first fill over the
//! 8-neighbourhood, ties broken by scan order: deterministic). Directions behind the
//! reference camera are pushed to the film border in their `x, y` direction.
//!
//! **Invariants:** a sky pixel's own centre direction returns that pixel's colour up to the
//! rounding of the projection (bilinear weight 1 on it within float error), so an identity
//! warp returns the input's sky pixels; the map is immutable after construction and the
//! lookup is a pure function of the direction (thread-count independent).
//!
//! No parameters.

use std::collections::VecDeque;

use glam::{Vec2, Vec3};
use parallax_core::{Image, Rgb};
use parallax_scene::camera::Pinhole;

/// Colours of the directions where a reference saw no surface (module docs).
#[derive(Clone, Debug)]
pub struct Environment {
    camera: Pinhole,
    /// Every pixel filled: sky pixels keep their colour, the others the nearest sky colour.
    filled: Image<Rgb>,
}

impl Environment {
    /// The environment of `color` seen by `camera`, where `sky[i]` marks the pixels without
    /// depth. `None` when there is no sky pixel (or the sizes disagree).
    pub fn from_sky(camera: &Pinhole, color: &Image<Rgb>, sky: &[bool]) -> Option<Self> {
        let (w, h) = (color.width() as usize, color.height() as usize);
        if sky.len() != w * h || (camera.width as usize, camera.height as usize) != (w, h) {
            return None;
        }
        // Multi-source BFS from every sky pixel: `src[i]` = the sky pixel `i` copies.
        let mut src = vec![usize::MAX; w * h];
        let mut queue = VecDeque::new();
        for (i, _) in sky.iter().enumerate().filter(|(_, s)| **s) {
            src[i] = i;
            queue.push_back(i);
        }
        if queue.is_empty() {
            return None;
        }
        while let Some(i) = queue.pop_front() {
            let (x, y) = ((i % w) as isize, (i / w) as isize);
            for (dx, dy) in [
                (-1, 0),
                (1, 0),
                (0, -1),
                (0, 1),
                (-1, -1),
                (1, -1),
                (-1, 1),
                (1, 1),
            ] {
                let (nx, ny) = (x + dx, y + dy);
                if nx < 0 || ny < 0 || nx >= w as isize || ny >= h as isize {
                    continue;
                }
                let j = ny as usize * w + nx as usize;
                if src[j] == usize::MAX {
                    src[j] = src[i];
                    queue.push_back(j);
                }
            }
        }
        let data = color.data();
        let filled = src.iter().map(|&s| data[s]).collect();
        Some(Self {
            camera: camera.clone(),
            filled: Image::from_vec(w as u32, h as u32, filled).ok()?,
        })
    }

    /// The colour seen in world direction `dir` (module docs; `dir` need not be normalised).
    pub fn lookup(&self, dir: Vec3) -> Rgb {
        let (w, h) = (self.filled.width(), self.filled.height());
        let c = self.camera.frame.basis.transpose() * dir;
        let film = if c.z < 0.0 {
            self.camera.film_of_camera_point(c)
        } else {
            None
        };
        let film = film.unwrap_or_else(|| {
            // Behind the camera (or on its plane): towards the border in the x, y direction.
            let centre = Vec2::new(w as f32, h as f32) * 0.5;
            let d = Vec2::new(c.x, -c.y);
            if d.length_squared() > 0.0 {
                centre + d.normalize() * (w + h) as f32
            } else {
                centre
            }
        });
        if !(film.x.is_finite() && film.y.is_finite()) {
            return *self.filled.get(w / 2, h / 2);
        }
        // Bilinear between the pixel centres around `film`, clamped to the border.
        let p = film - Vec2::splat(0.5);
        let (fx, fy) = (p.x.floor(), p.y.floor());
        let (tx, ty) = (p.x - fx, p.y - fy);
        let clampx = |v: f32| v.clamp(0.0, (w - 1) as f32) as u32;
        let clampy = |v: f32| v.clamp(0.0, (h - 1) as f32) as u32;
        let (x0, x1) = (clampx(fx), clampx(fx + 1.0));
        let (y0, y1) = (clampy(fy), clampy(fy + 1.0));
        let g = |x, y| *self.filled.get(x, y);
        let top = g(x0, y0) * (1.0 - tx) + g(x1, y0) * tx;
        let bottom = g(x0, y1) * (1.0 - tx) + g(x1, y1) * tx;
        top * (1.0 - ty) + bottom * ty
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use parallax_scene::CameraDesc;

    fn camera(w: u32, h: u32) -> Pinhole {
        let d = CameraDesc::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0);
        Pinhole::new(&d, w, h).unwrap()
    }

    #[test]
    fn pixel_centre_directions_return_sky_colours_and_surfaces_the_nearest_sky() {
        let cam = camera(8, 4);
        let data: Vec<Rgb> = (0..32)
            .map(|i| Rgb::new(i as f32 / 32.0, 0.5, 1.0 - i as f32 / 32.0))
            .collect();
        let color = Image::from_vec(8, 4, data.clone()).unwrap();
        // Bottom two rows are a surface.
        let sky: Vec<bool> = (0..32).map(|i| i < 16).collect();
        let env = Environment::from_sky(&cam, &color, &sky).unwrap();
        for i in 0..16u32 {
            let (x, y) = (i % 8, i / 8);
            let dir = cam
                .frame
                .dir_to_world(cam.camera_dir(Vec2::new(x as f32 + 0.5, y as f32 + 0.5)));
            let c = env.lookup(dir);
            assert!((c - data[i as usize]).abs().max_element() < 1e-5, "{x},{y}");
        }
        // A surface pixel takes a sky pixel at the least chessboard distance (two rows up,
        // 8-neighbourhood BFS): one of row 1's pixels with |x - 3| <= 2.
        let dir = cam.frame.dir_to_world(cam.camera_dir(Vec2::new(3.5, 3.5)));
        let c = env.lookup(dir);
        assert!(
            (9..=13).any(|k| (c - data[k]).abs().max_element() < 1e-5),
            "{c}"
        );
        // Behind the camera and far outside: a border colour, finite.
        assert!(env.lookup(Vec3::Z).is_finite());
        assert!(env.lookup(Vec3::new(1e6, 0.0, -1.0)).is_finite());
        assert!(Environment::from_sky(&cam, &color, &[false; 32]).is_none());
    }
}

//! Multiple importance sampling (Veach & Guibas 1995, §4): the power heuristic with
//! exponent 2, as Mitsuba 3's `path` integrator weighs its BSDF and emitter samples.

/// Weight of a sample drawn with density `pdf_a` when the other strategy would have drawn it
/// with `pdf_b`: `pdf_a² / (pdf_a² + pdf_b²)`; 0 where that is not finite (both zero).
#[inline]
pub fn power_heuristic(pdf_a: f32, pdf_b: f32) -> f32 {
    let (a, b) = (pdf_a * pdf_a, pdf_b * pdf_b);
    let w = a / (a + b);
    if w.is_finite() { w } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use parallax_core::sampling::Rng;

    #[test]
    fn the_two_weights_of_a_direction_sum_to_one() {
        let mut rng = Rng::new(1, 2);
        for _ in 0..10_000 {
            // Densities over many orders of magnitude, as BSDF and light pdfs are.
            let a = (rng.next_f32() * 40.0 - 20.0).exp2();
            let b = (rng.next_f32() * 40.0 - 20.0).exp2();
            let s = power_heuristic(a, b) + power_heuristic(b, a);
            assert!((s - 1.0).abs() < 1e-6, "{a} {b}: {s}");
        }
        assert_eq!(power_heuristic(1.0, 0.0), 1.0);
        assert_eq!(power_heuristic(0.0, 1.0), 0.0);
        assert_eq!(power_heuristic(0.0, 0.0), 0.0);
    }
}

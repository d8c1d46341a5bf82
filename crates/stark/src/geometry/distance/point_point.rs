//! Point–point squared distance.

use nalgebra::Vector3;

/// Squared distance between two points, `|p0 − p1|²`.
///
/// NaN in, NaN out.
#[inline]
pub fn point_point_distance_sq(p0: &Vector3<f64>, p1: &Vector3<f64>) -> f64 {
    (p0 - p1).norm_squared()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_form() {
        let a = Vector3::new(1.0, 2.0, 3.0);
        let b = Vector3::new(4.0, 6.0, 3.0);
        assert_eq!(point_point_distance_sq(&a, &b), 25.0);
        assert_eq!(point_point_distance_sq(&a, &a), 0.0);
    }

    #[test]
    fn tiny_and_nan() {
        let a = Vector3::new(1e-300, 0.0, 0.0);
        // Underflows to zero: squared distances below ~1e-308 are not representable.
        assert_eq!(point_point_distance_sq(&a, &Vector3::zeros()), 0.0);
        let n = Vector3::new(f64::NAN, 0.0, 0.0);
        assert!(point_point_distance_sq(&n, &a).is_nan());
    }
}

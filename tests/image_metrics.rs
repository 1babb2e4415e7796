//! Image type helpers, error metrics and the false-colour error image.

use vkvcm::image::{
    compare, error_ramp, false_color_error, false_color_error_scaled, luminance, Image, REL_MSE_EPSILON,
};

#[test]
fn image_basics() {
    let mut img = Image::from_fn(3, 2, |x, y| [x as f32, y as f32, 1.0]);
    assert_eq!(img.pixel_count(), 6);
    assert_eq!(img.get(2, 1), [2.0, 1.0, 1.0]);
    assert_eq!(img.index(1, 1), 4);
    img.set(0, 1, [9.0, 9.0, 9.0]);
    assert_eq!(img.data[3], [9.0; 3]);
    assert_eq!(Image::new(2, 2).mean(), [0.0; 3]);
    assert_eq!(Image::filled(4, 4, [1.0, 2.0, 3.0]).mean(), [1.0, 2.0, 3.0]);
    assert!((Image::filled(1, 1, [1.0; 3]).mean_luminance() - 1.0).abs() < 1e-6);
    assert!((luminance([1.0, 1.0, 1.0]) - 1.0).abs() < 1e-6);
    assert!(Image::from_data(2, 2, vec![[0.0; 3]; 3]).is_err());

    let avg = Image::average(&[Image::filled(2, 1, [1.0; 3]), Image::filled(2, 1, [3.0; 3])]).unwrap();
    assert_eq!(avg, Image::filled(2, 1, [2.0; 3]));
    assert!(Image::average(&[Image::new(2, 1), Image::new(1, 2)]).is_err());
    assert!(Image::average(&[]).is_err());

    let big = Image::from_fn(5, 4, |x, y| [(x + 10 * y) as f32, 1.0, 0.0]);
    let small = big.downsample(2);
    assert_eq!((small.width, small.height), (2, 2));
    assert_eq!(small.get(0, 0)[0], (0.0 + 1.0 + 10.0 + 11.0) / 4.0);
    assert_eq!(small.get(1, 1)[0], (22.0 + 23.0 + 32.0 + 33.0) / 4.0);
    assert_eq!(big.crop(1, 2, 2, 2).get(1, 1), big.get(2, 3));

    let mut bad = Image::new(2, 2);
    bad.set(1, 1, [f32::NAN, 0.0, 0.0]);
    bad.set(0, 1, [0.0, f32::NEG_INFINITY, 0.0]);
    assert_eq!(bad.non_finite_count(), 2);
    let mut s = Image::filled(1, 1, [1.0, 2.0, 3.0]);
    s.scale(2.0);
    assert_eq!(s.get(0, 0), [2.0, 4.0, 6.0]);
}

#[test]
#[should_panic(expected = "outside")]
fn get_out_of_bounds_panics() {
    Image::new(2, 2).get(2, 0);
}

#[test]
fn metrics_known_values() {
    let reference = Image::filled(2, 1, [1.0, 0.0, 0.5]);
    let mut a = reference.clone();
    let m = compare(&a, &reference).unwrap();
    assert_eq!((m.rmse, m.rel_mse, m.mean_abs_bias, m.max_abs), (0.0, 0.0, 0.0, 0.0));

    // Errors over 6 values: +0.5 (R of pixel 0), -0.1 (G of pixel 1), rest 0.
    a.data[0][0] = 1.5;
    a.data[1][1] = -0.1;
    let m = compare(&a, &reference).unwrap();
    let mse = (0.25 + 0.01) / 6.0;
    assert!((m.rmse - f64::sqrt(mse)).abs() < 1e-7, "{m}");
    let rel = (0.25 / (1.0 + REL_MSE_EPSILON) + 0.01 / (0.0 + REL_MSE_EPSILON)) / 6.0;
    assert!((m.rel_mse - rel).abs() < 1e-6, "{m}");
    assert!((m.mean_abs_bias - 0.4 / 6.0).abs() < 1e-7, "{m}");
    assert!((m.max_abs - 0.5).abs() < 1e-7, "{m}");
    assert_eq!(REL_MSE_EPSILON, 1e-2);

    // The bias is the absolute value of the signed mean: symmetric errors cancel.
    let b = Image::from_data(2, 1, vec![[1.1, 0.0, 0.5], [0.9, 0.0, 0.5]]).unwrap();
    let m = compare(&b, &Image::filled(2, 1, [1.0, 0.0, 0.5])).unwrap();
    assert!(m.mean_abs_bias < 1e-7 && m.rmse > 0.05, "{m}");
    assert!(m.to_string().contains("rmse"));

    assert!(compare(&Image::new(2, 2), &Image::new(2, 3)).unwrap_err().to_string().contains("2x3"));
    let mut nan = reference.clone();
    nan.data[1][2] = f32::NAN;
    let m = compare(&nan, &reference).unwrap();
    assert!(m.rmse.is_nan() && m.max_abs.is_nan() && m.mean_abs_bias.is_nan(), "{m}");
}

#[test]
fn false_color_error_image() {
    let a = Image::from_fn(100, 1, |x, _| [x as f32 / 100.0, 0.0, 0.0]);
    let b = Image::new(100, 1);
    // Equal images: all black.
    assert!(false_color_error(&a, &a).data.iter().all(|p| *p == [0.0; 3]));
    let fc = false_color_error(&a, &b);
    assert_eq!((fc.width, fc.height), (100, 1));
    assert_eq!(fc.get(0, 0), [0.0; 3]);
    // The 99th percentile (and above) reaches the top of the ramp (red).
    assert_eq!(fc.get(99, 0), error_ramp(1.0));
    assert_eq!(error_ramp(1.0), error_ramp(5.0));
    assert_eq!(error_ramp(0.0), [0.0; 3]);
    let top = error_ramp(1.0);
    assert!(top[0] > 0.9 && top[1] < 0.05 && top[2] < 0.01, "{top:?}");
    assert_eq!(error_ramp(f32::NAN), [1.0, 0.0, 1.0]);
    // Monotone brightness along the ramp's first half, distinct colours everywhere.
    assert!(luminance(error_ramp(0.1)) < luminance(error_ramp(0.4)));
    // Fixed scale.
    let fixed = false_color_error_scaled(&a, &b, 2.0);
    assert_eq!(fixed.get(99, 0), error_ramp(luminance([0.99, 0.0, 0.0]) / 2.0));
    // Non-finite errors are flagged.
    let mut n = a.clone();
    n.set(5, 0, [f32::NAN, 0.0, 0.0]);
    assert_eq!(false_color_error(&n, &b).get(5, 0), [1.0, 0.0, 1.0]);
}

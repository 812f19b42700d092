//! From linear radiance to the PNG: clamp to [0, 1], the sRGB transfer function, 8 bits.

use image::codecs::png::PngEncoder;
use image::{ColorType, ImageEncoder};
use rdbvh_core::Vec3;

use super::light::luminance;
use super::RenderError;

/// The sRGB transfer function (IEC 61966-2-1) of a linear value, clamped to [0, 1] first.
pub fn srgb(linear: f32) -> f32 {
    let c = linear.clamp(0.0, 1.0);
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// 8-bit sRGB bytes, RGB, row-major, of linear `pixels` (NaN becomes 0).
pub fn to_srgb8(pixels: &[Vec3]) -> Vec<u8> {
    pixels
        .iter()
        .flat_map(|p| p.to_array())
        .map(|c| (srgb(c) * 255.0 + 0.5) as u8)
        .collect()
}

/// The PNG file of a `width x height` image of 8-bit RGB bytes.
pub fn encode_png(rgb: &[u8], width: u32, height: u32) -> Result<Vec<u8>, RenderError> {
    let mut png = Vec::new();
    PngEncoder::new(&mut png)
        .write_image(rgb, width, height, ColorType::Rgb8)
        .map_err(|e| RenderError::Encode(e.to_string()))?;
    Ok(png)
}

/// The mean Rec. 709 luminance of the linear image, before tone mapping.
pub fn mean_luminance(pixels: &[Vec3]) -> f64 {
    if pixels.is_empty() {
        return 0.0;
    }
    pixels.iter().map(|&p| f64::from(luminance(p))).sum::<f64>() / pixels.len() as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transfer_function_ends_and_middle() {
        assert_eq!(srgb(-1.0), 0.0);
        assert_eq!(srgb(0.0), 0.0);
        assert!((srgb(1.0) - 1.0).abs() < 1e-6);
        assert_eq!(srgb(7.0), srgb(1.0));
        // Linear 0.214 is sRGB 0.5.
        assert!((srgb(0.214) - 0.5).abs() < 1e-3);
        assert_eq!(to_srgb8(&[Vec3::new(0.0, 1.0, f32::NAN)]), vec![0, 255, 0]);
    }

    #[test]
    fn png_round_trips() {
        let rgb = to_srgb8(&[Vec3::ZERO, Vec3::ONE, Vec3::X, Vec3::splat(0.214)]);
        let png = encode_png(&rgb, 2, 2).unwrap();
        let back = image::load_from_memory(&png).unwrap().to_rgb8();
        assert_eq!(back.into_raw(), rgb);
    }
}

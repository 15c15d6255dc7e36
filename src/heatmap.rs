//! False-colour images of a signed per-pixel quantity with a labelled
//! colour bar (`glint diff --diff OUT.png`): blue below zero, light grey at
//! zero, red above, saturating at +-range; NaN is magenta. Small images are
//! enlarged by whole pixels (nearest) so a person can see them.

use plotters::prelude::*;

use crate::chart::{ChartError, FONT, register_font};

/// Width of the margin holding the colour bar and its labels.
const BAR_MARGIN: u32 = 150;
/// Smallest canvas height (room for the bar's labels).
const MIN_HEIGHT: u32 = 220;

/// A diverging map (the ends of Moreland's cool-warm map), `t` in [-1, 1].
pub fn colour(t: f32) -> [u8; 3] {
    if t.is_nan() {
        return [255, 0, 255];
    }
    let t = t.clamp(-1.0, 1.0);
    let mid = [221.0, 221.0, 221.0];
    let end = if t < 0.0 {
        [59.0, 76.0, 192.0]
    } else {
        [180.0, 4.0, 38.0]
    };
    let a = t.abs();
    std::array::from_fn(|c| (mid[c] + (end[c] - mid[c]) * a).round() as u8)
}

/// RGB8 pixels of the picture and its canvas size: `values` (row-major,
/// `width` x `height`) mapped through [`colour`] at `values / range`, with
/// the colour bar titled `label` on the right.
pub fn render(
    width: u32,
    height: u32,
    values: &[f32],
    range: f32,
    label: &str,
) -> Result<(u32, u32, Vec<u8>), ChartError> {
    assert_eq!(values.len(), width as usize * height as usize);
    register_font()?;
    let k = (512 / width.max(height)).clamp(1, 16);
    let (iw, ih) = (width * k, height * k);
    let (cw, ch) = (iw + BAR_MARGIN, ih.max(MIN_HEIGHT));
    let mut buf = vec![255u8; (cw * ch * 3) as usize];
    let mut put = |x: u32, y: u32, c: [u8; 3]| {
        let i = ((y * cw + x) * 3) as usize;
        buf[i..i + 3].copy_from_slice(&c);
    };
    for y in 0..ih {
        for x in 0..iw {
            let v = values[((y / k) * width + x / k) as usize];
            put(x, y, colour(v / range));
        }
    }
    // The bar: top = +range, bottom = -range.
    let (bx, bw, top, bottom) = (iw + 16, 18, 30, ch - 16);
    for y in top..bottom {
        let t = 1.0 - 2.0 * (y - top) as f32 / (bottom - top - 1) as f32;
        for x in bx..bx + bw {
            put(x, y, colour(t));
        }
    }
    {
        let root = BitMapBackend::with_buffer(&mut buf, (cw, ch)).into_drawing_area();
        let e = |e: &dyn std::fmt::Display| ChartError(e.to_string());
        let style = TextStyle::from((FONT, 13).into_font()).color(&BLACK);
        root.draw_text(label, &style, (iw as i32 + 6, 8))
            .map_err(|x| e(&x))?;
        for i in 0..=4 {
            let t = 1.0 - i as f32 / 2.0;
            let y = top as f32 + (1.0 - t) / 2.0 * (bottom - top - 1) as f32;
            let text = format!("{:+}", t * range);
            root.draw_text(
                if i == 2 { "0" } else { &text },
                &style,
                ((bx + bw + 6) as i32, y as i32 - 6),
            )
            .map_err(|x| e(&x))?;
        }
        root.present().map_err(|x| e(&x))?;
    }
    Ok((cw, ch, buf))
}

/// [`render`] as PNG bytes.
pub fn png(
    width: u32,
    height: u32,
    values: &[f32],
    range: f32,
    label: &str,
) -> Result<Vec<u8>, ChartError> {
    let (w, h, buf) = render(width, height, values, range, label)?;
    let img = image::RgbImage::from_raw(w, h, buf).expect("sized buffer");
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png)
        .map_err(|e| ChartError(e.to_string()))?;
    Ok(out.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colours_and_layout() {
        assert_eq!(colour(0.0), [221, 221, 221]);
        assert_eq!(colour(-1.0), [59, 76, 192]);
        assert_eq!(colour(7.0), [180, 4, 38]);
        assert_eq!(colour(f32::NAN), [255, 0, 255]);
        let v = [-4.0f32, 0.0, 4.0, f32::NAN];
        let (w, h, buf) = render(2, 2, &v, 4.0, "z").unwrap();
        // 2x2 enlarged 16x (capped) plus the bar's margin.
        assert_eq!((w, h), (32 + BAR_MARGIN, MIN_HEIGHT));
        let px = |x: u32, y: u32| {
            let i = ((y * w + x) * 3) as usize;
            [buf[i], buf[i + 1], buf[i + 2]]
        };
        assert_eq!(px(0, 0), colour(-1.0));
        assert_eq!(px(31, 31), [255, 0, 255]);
        assert_eq!(px(20, 3), colour(0.0));
    }
}

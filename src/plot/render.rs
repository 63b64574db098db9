//! Rendering a [`Figure`] to `stem.svg` (with a `<title>`) and `stem.png`, with the bundled
//! DejaVu Sans registered first so no system fonts are needed.

use std::path::Path;

use plotters::prelude::*;

use super::{de, Figure, FONT};
use crate::atomic::write_atomically;
use crate::error::{Error, Result};

/// A figure written as `stem.svg` and `stem.png`.
#[derive(Debug, Clone, PartialEq)]
pub struct FigureInfo {
    pub stem: String,
    pub title: String,
    pub width: u32,
    pub height: u32,
}

/// Register the shipped DejaVu Sans as [`FONT`] (once per process).
fn register_fonts() -> Result<()> {
    static FONT_BYTES: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");
    static REGISTERED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(FONT, FontStyle::Normal, FONT_BYTES).is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(Error::Other(
            "the figures' font (assets/DejaVuSans.ttf) could not be loaded".into(),
        ))
    }
}

/// Draw `fig` to `stem.svg` (with a `<title>`) and `stem.png` in `dir`, both written atomically.
/// The two are drawn side by side (the SVG's text and the bitmap's rasterising are each about
/// half of a figure's time, and share nothing but the figure); their bytes do not depend on it.
pub fn render<F: Figure + Sync>(dir: &Path, fig: &F) -> Result<FigureInfo> {
    register_fonts()?;
    let (svg, png) = rayon::join(|| write_svg(dir, fig), || write_png(dir, fig));
    svg?;
    png?;
    Ok(FigureInfo {
        stem: fig.stem().into(),
        title: fig.title(),
        width: fig.size().0,
        height: fig.size().1,
    })
}

/// `stem.svg` of `fig`, with its title.
fn write_svg<F: Figure>(dir: &Path, fig: &F) -> Result<()> {
    let (w, h) = fig.size();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(de)?;
        fig.draw(&root)?;
        root.present().map_err(de)?;
    }
    let svg = with_svg_title(&svg, &fig.title());
    let svg_path = dir.join(format!("{}.svg", fig.stem()));
    write_atomically(&svg_path, |out| {
        out.write_all(svg.as_bytes())
            .map_err(|e| Error::io(&svg_path, e))
    })
}

/// `stem.png` of `fig`.
fn write_png<F: Figure>(dir: &Path, fig: &F) -> Result<()> {
    let (w, h) = fig.size();
    let mut pixels = vec![0u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut pixels, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(de)?;
        fig.draw(&root)?;
        root.present().map_err(de)?;
    }
    let png_path = dir.join(format!("{}.png", fig.stem()));
    write_atomically(&png_path, |out| {
        let bad = |e: png::EncodingError| Error::Other(format!("{}: {e}", png_path.display()));
        let mut encoder = png::Encoder::new(out, w, h);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(bad)?;
        writer.write_image_data(&pixels).map_err(bad)?;
        writer.finish().map_err(bad)
    })
}

/// The SVG text with a `<title>` element right after the root's opening tag.
fn with_svg_title(svg: &str, title: &str) -> String {
    let Some(start) = svg.find("<svg") else {
        return svg.to_string();
    };
    let Some(end) = svg[start..].find('>') else {
        return svg.to_string();
    };
    let at = start + end + 1;
    format!(
        "{}\n<title>{}</title>{}",
        &svg[..at],
        escape(title),
        &svg[at..]
    )
}

/// Escape text for XML/HTML content and attribute values.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_title_goes_inside_the_root_element_escaped() {
        let svg = "<?xml?>\n<svg width=\"1\">\n<rect/></svg>";
        let out = with_svg_title(svg, "a < b");
        assert_eq!(
            out,
            "<?xml?>\n<svg width=\"1\">\n<title>a &lt; b</title>\n<rect/></svg>"
        );
        assert_eq!(with_svg_title("no root", "t"), "no root");
    }
}

//! Connected regions of a thresholded image.

/// One 4-connected region of pixels on the same side of the threshold.
#[derive(Clone, Debug, PartialEq)]
pub struct Region {
    /// Its label in the label map.
    pub label: u32,
    /// Whether its pixels are above the threshold.
    pub bright: bool,
    /// Number of pixels.
    pub pixels: usize,
    /// Whether it touches the border of the searched rectangle.
    pub touches_border: bool,
    /// Its first pixel in raster order `(i, j)` (column, row within the
    /// rectangle): a pixel of its outer boundary whose left neighbour is
    /// outside it.
    pub first: (usize, usize),
}

/// Label the 4-connected regions of the mask `above` (`w x h`, row-major).
/// Returns the label of every pixel (labels start at 0) and the regions,
/// indexed by label.
pub fn label(above: &[bool], w: usize, h: usize) -> (Vec<u32>, Vec<Region>) {
    const NONE: u32 = u32::MAX;
    let mut labels = vec![NONE; w * h];
    let mut regions = Vec::new();
    let mut stack = Vec::new();
    for start in 0..w * h {
        if labels[start] != NONE {
            continue;
        }
        let id = regions.len() as u32;
        let bright = above[start];
        let mut region = Region {
            label: id,
            bright,
            pixels: 0,
            touches_border: false,
            first: (start % w, start / w),
        };
        labels[start] = id;
        stack.push(start);
        while let Some(k) = stack.pop() {
            let (i, j) = (k % w, k / w);
            region.pixels += 1;
            if i == 0 || j == 0 || i + 1 == w || j + 1 == h {
                region.touches_border = true;
            }
            let mut visit = |n: usize| {
                if labels[n] == NONE && above[n] == bright {
                    labels[n] = id;
                    stack.push(n);
                }
            };
            if i > 0 {
                visit(k - 1);
            }
            if i + 1 < w {
                visit(k + 1);
            }
            if j > 0 {
                visit(k - w);
            }
            if j + 1 < h {
                visit(k + w);
            }
        }
        regions.push(region);
    }
    (labels, regions)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_blobs_and_the_ground() {
        // 6x4: ground, a 2x2 blob, a single pixel on the border.
        #[rustfmt::skip]
        let m = [
            false, false, false, false, false, true,
            false, true,  true,  false, false, false,
            false, true,  true,  false, false, false,
            false, false, false, false, false, false,
        ];
        let (labels, regions) = label(&m, 6, 4);
        assert_eq!(regions.len(), 3);
        let blob = &regions[labels[7] as usize];
        assert_eq!(
            (blob.pixels, blob.bright, blob.touches_border),
            (4, true, false)
        );
        assert_eq!(blob.first, (1, 1));
        let corner = &regions[labels[5] as usize];
        assert_eq!((corner.pixels, corner.touches_border), (1, true));
        assert_eq!(regions[labels[0] as usize].pixels, 19);
    }
}

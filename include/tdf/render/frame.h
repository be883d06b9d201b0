#pragma once
/// The images of one rendered view: one Image per requested pass plus the coverage.
#include <tdf/core/image.h>
#include <tdf/io/image_io.h>
#include <tdf/render/pass.h>

#include <vector>

namespace tdf {

struct Frame {
    std::vector<Pass> passes;   ///< in request order
    std::vector<Image> images;  ///< images[k] holds passes[k] (pass_channels() channels)
    Image coverage;             ///< 1 channel, always present: the mask pass's values

    /// The image of `pass`, or nullptr when it was not rendered.
    const Image* find(Pass pass) const;
    /// One EXR layer per pass with the conventional channel names (`albedo.R`, `depth.Z`, ...).
    std::vector<ExrLayer> exr_layers() const;
};

/// Reads a Frame back from layers written by Frame::exr_layers() (unknown layers are an error
/// naming `source`). Coverage comes from the mask layer, or is empty without one.
Frame frame_from_exr_layers(const std::vector<ExrLayer>& layers, const std::string& source);

/// An 8-bit-ready RGB preview of one pass in [0, 1]: colours as they are; vectors as
/// v * 0.5 + 0.5; depth min-max normalised over the covered pixels; uv as (u, v', 1); every
/// pass but albedo/lambertian/mask blended over white with the coverage, as the visualizer's
/// PNGs (spec 3.9).
Image preview_image(Pass pass, const Image& image, const Image& coverage);

}  // namespace tdf

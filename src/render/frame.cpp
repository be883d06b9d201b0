#include <tdf/render/frame.h>

#include <tdf/core/error.h>

#include <algorithm>
#include <limits>

namespace tdf {

const Image* Frame::find(Pass pass) const {
    for (std::size_t k = 0; k < passes.size(); ++k)
        if (passes[k] == pass) return &images[k];
    return nullptr;
}

std::vector<ExrLayer> Frame::exr_layers() const {
    std::vector<ExrLayer> layers;
    for (std::size_t k = 0; k < passes.size(); ++k)
        layers.push_back({pass_name(passes[k]), pass_info(passes[k]).channels, images[k]});
    return layers;
}

Frame frame_from_exr_layers(const std::vector<ExrLayer>& layers, const std::string& source) {
    Frame frame;
    for (const ExrLayer& layer : layers) {
        Pass pass;
        try {
            pass = parse_pass(layer.name);
        } catch (const Error& e) {
            throw_error("{}: layer '{}': {}", source, layer.name, e.what());
        }
        if (layer.image.channels() != pass_channels(pass))
            throw_error("{}: layer '{}' has {} channels, expected {}", source, layer.name, layer.image.channels(),
                        pass_channels(pass));
        frame.passes.push_back(pass);
        frame.images.push_back(layer.image);
        if (pass == Pass::Mask) frame.coverage = layer.image;
    }
    return frame;
}

Image preview_image(Pass pass, const Image& image, const Image& coverage) {
    const PassInfo& info = pass_info(pass);
    const int w = image.width(), h = image.height(), c = image.channels();
    TDF_CHECK(coverage.width() == w && coverage.height() == h);
    Image out(w, h, 3);
    float depth_lo = std::numeric_limits<float>::max(), depth_hi = std::numeric_limits<float>::lowest();
    if (pass == Pass::Depth)
        for (std::size_t i = 0; i < image.pixel_count(); ++i)
            if (coverage.data()[i] > 0.f) {
                depth_lo = std::min(depth_lo, image.data()[i]);
                depth_hi = std::max(depth_hi, image.data()[i]);
            }
    const bool over_white = pass != Pass::Albedo && pass != Pass::Lambertian && pass != Pass::Mask;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float* in = image.pixel(x, y);
            float* o = out.pixel(x, y);
            for (int k = 0; k < 3; ++k) {
                float v = c == 1 ? in[0] : k < c ? in[k] : 1.f;  // uv: (u, v', 1)
                if (info.is_vector) v = v * 0.5f + 0.5f;
                if (pass == Pass::Depth)
                    v = depth_hi > depth_lo ? (in[0] - depth_lo) / (depth_hi - depth_lo) : 0.f;
                o[k] = v;
            }
            if (over_white) {
                const float a = std::clamp(coverage.at(x, y, 0), 0.f, 1.f);
                for (int k = 0; k < 3; ++k) o[k] = a * o[k] + (1.f - a);
            }
        }
    return out;
}

}  // namespace tdf

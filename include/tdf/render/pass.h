#pragma once
/// Render passes: the reference's names (spec 3.2, 3.9), channel layouts and backgrounds.
/// EXR files store each pass as a layer `<name>.<channel>` with the values below (not remapped
/// to [0,1]; PNG previews remap vectors with v * 0.5 + 0.5 and show the background white).
#include <string>
#include <vector>

namespace tdf {

enum class Pass {
    Albedo,                  ///< RGB base colour, composited over the background colour
    Lambertian,              ///< RGB albedo x shade (training or visualizer shading), composited
    Mask,                    ///< coverage: 1 hit, 0 background (fractional after SSAA)
    Depth,                   ///< -z_cam, 0 background
    Normal,                  ///< XYZ interpolated unit vertex normal N (world), 0 background
    Tangent,                 ///< XYZ interpolated unit tangent T (world), 0 background
    Uv,                      ///< UV as the reference writes it: (u, 1 - v), 0 background
    TactileNormal,           ///< XYZ tangent-space tactile normal sampled from the map, 0 background
    ShadingNormal,           ///< XYZ world shading normal (TBN composition), 0 background
    ShadingNormalViewspace,  ///< XYZ camera-space shading normal (x right, y up, z to viewer)
    Label,                   ///< RGB label map sampled at the UVs, 0 background
};

/// Number of Pass values.
constexpr int kPassCount = int(Pass::Label) + 1;

struct PassInfo {
    Pass pass;
    const char* name;                       ///< spec name, e.g. "shading_normal_viewspace"
    std::vector<std::string> channels;      ///< EXR channel suffixes, e.g. {"X", "Y", "Z"}
    bool is_vector;                         ///< values in [-1, 1] (PNG preview: v * 0.5 + 0.5)
};

/// Every pass, in enum order.
const std::vector<PassInfo>& all_passes();
const PassInfo& pass_info(Pass pass);
const char* pass_name(Pass pass);
int pass_channels(Pass pass);
/// Full EXR channel names, e.g. {"albedo.R", "albedo.G", "albedo.B"}.
std::vector<std::string> pass_channel_names(Pass pass);
/// Parses a pass name; throws tdf::Error "unknown pass 'x' (valid: albedo, lambertian, ...)".
Pass parse_pass(const std::string& name);
/// "albedo, lambertian, ..." for messages and help texts.
std::string pass_name_list();

}  // namespace tdf

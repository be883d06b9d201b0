#include <tdf/render/pass.h>

#include <tdf/core/error.h>

namespace tdf {

const std::vector<PassInfo>& all_passes() {
    static const std::vector<PassInfo> passes = {
        {Pass::Albedo, "albedo", {"R", "G", "B"}, false},
        {Pass::Lambertian, "lambertian", {"R", "G", "B"}, false},
        {Pass::Mask, "mask", {"Y"}, false},
        {Pass::Depth, "depth", {"Z"}, false},
        {Pass::Normal, "normal", {"X", "Y", "Z"}, true},
        {Pass::Tangent, "tangent", {"X", "Y", "Z"}, true},
        {Pass::Uv, "uv", {"U", "V"}, false},
        {Pass::TactileNormal, "tactile_normal", {"X", "Y", "Z"}, true},
        {Pass::ShadingNormal, "shading_normal", {"X", "Y", "Z"}, true},
        {Pass::ShadingNormalViewspace, "shading_normal_viewspace", {"X", "Y", "Z"}, true},
        {Pass::Label, "label", {"R", "G", "B"}, false},
    };
    TDF_CHECK_EQ(passes.size(), std::size_t(kPassCount));
    return passes;
}

const PassInfo& pass_info(Pass pass) { return all_passes()[std::size_t(pass)]; }

const char* pass_name(Pass pass) { return pass_info(pass).name; }

int pass_channels(Pass pass) { return int(pass_info(pass).channels.size()); }

std::vector<std::string> pass_channel_names(Pass pass) {
    std::vector<std::string> names;
    for (const auto& c : pass_info(pass).channels) names.push_back(std::string(pass_name(pass)) + "." + c);
    return names;
}

std::string pass_name_list() {
    std::string list;
    for (const auto& info : all_passes()) list += (list.empty() ? "" : ", ") + std::string(info.name);
    return list;
}

Pass parse_pass(const std::string& name) {
    for (const auto& info : all_passes())
        if (name == info.name) return info.pass;
    throw_error("unknown pass '{}' (valid: {})", name, pass_name_list());
}

}  // namespace tdf

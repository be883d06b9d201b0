#include <tdf/guidance/schedule.h>

#include <tdf/core/error.h>

#include <algorithm>
#include <cctype>
#include <cmath>

namespace tdf {

const char* const kNegativePrompt =
    "bad quality, blurred, low resolution, low quality, worst quality, low res, glitch, deformed, "
    "mutated, ugly, disfigured";
const char* const kPromptSuffix = ", highly detailed, hd, best quality, front lighting";
const char* const kTactilePrompt = "sks normal map";

double step_ratio(int iteration, int iters_init, int iters_total) {
    TDF_CHECK_LT(iters_init, iters_total);
    const int step = iteration + 1;
    // Matches reference: Python true division in double precision, then min(1, .) (spec 5.1).
    return std::min(1.0, double(step - iters_init) / double(iters_total - iters_init));
}

double visual_guidance_strength(int iteration, int iters_init, int iters_total) {
    // Same operation order as the reference, so that int(50 * strength) floors identically.
    return kVisualStrengthStart +
           step_ratio(iteration, iters_init, iters_total) * (kVisualStrengthEnd - kVisualStrengthStart);
}

std::vector<int> ddim_timesteps(int steps) {
    TDF_CHECK(steps >= 1 && steps <= 1000);
    // DDIM "leading" spacing with steps_offset = 1 over 1000 training steps (spec 5.4).
    const int ratio = 1000 / steps;
    std::vector<int> timesteps(static_cast<std::size_t>(steps));
    for (int k = 0; k < steps; ++k) timesteps[std::size_t(k)] = (steps - 1 - k) * ratio + 1;
    return timesteps;
}

int ddim_start_index(double strength, int steps) {
    if (!(strength >= 0.0 && strength <= 1.0))
        throw_error("guidance strength {} is outside [0, 1]", strength);
    // Matches reference: init_step = int(steps * strength), truncation (spec 5.4, 13.21). The
    // reference would index past the end for strength 1; clamp to the last step instead.
    return std::min(int(double(steps) * strength), steps - 1);
}

int ddim_start_timestep(double strength, int steps) {
    return ddim_timesteps(steps)[std::size_t(ddim_start_index(strength, steps))];
}

double denoise_fraction(double strength, int steps) {
    return double(steps - ddim_start_index(strength, steps)) / double(steps);
}

const std::vector<TextureDescription>& texture_descriptions() {
    // Matches reference: texture_desc.json, all 28 entries in file order (spec 5.7). The paper's
    // table (appendix) words some of them differently; the code's file is what ran.
    static const std::vector<TextureDescription> table = {
        {"avocado", "avocado skin's"},
        {"cantaloupe", "cantaloupe skin's"},
        {"ClothBag", "canvas bag's"},
        {"CorkMat", "cork mat"},
        {"CuttingBoard", "cutting board's"},
        {"GreenSweater", "crochet"},
        {"MetalFrame", "metal grid's"},
        {"OrangeGlove", "heat resistant rubber with heart-shape pattern"},
        {"PinkCloth", "cleaning cloth's"},
        {"PurpleGlove", "thin rubber with grid pattern"},
        {"RedCloth1", "patterned table cloth's"},
        {"RedCloth2", "soft table cloth's"},
        {"SpongeHard", "heavy duty sponge's"},
        {"SpongeSoft", "soft sponge's"},
        {"WhiteSponge", "shelf cabinet liner's"},
        {"Corn", "corn"},
        {"Football", "football leather"},
        {"FootballHandle", "football laces"},
        {"GlassTumbler", "firm elastic fabric"},
        {"GoldGoat", "fine striped steel"},
        {"Orange", "orange"},
        {"Potato", "potato"},
        {"Strawberry", "strawberry"},
        {"StrawHat", "straw hat's woven"},
        {"TableTennisFace", "dotted firm rubber"},
        {"TableTennisHandle", "smooth wood"},
        {"Avocado", "avocado skin's"},
        {"BlackBase", "flat"},
    };
    return table;
}

std::string texture_description(const std::string& texture) {
    std::string known;
    for (const auto& entry : texture_descriptions()) {
        if (texture == entry.texture) return entry.description;
        known += known.empty() ? "" : ", ";
        known += entry.texture;
    }
    throw_error("texture '{}' has no text description (known: {})", texture, known);
}

namespace {
bool all_digits(const std::string& token) {
    // Python str.isdigit(): false for the empty string.
    return !token.empty() &&
           std::all_of(token.begin(), token.end(), [](unsigned char c) { return std::isdigit(c) != 0; });
}
}  // namespace

std::string object_words(const std::string& mesh_obj) {
    std::string words;
    bool first = true;
    std::size_t start = 0;
    while (true) {
        const auto end = mesh_obj.find('_', start);
        const std::string token = mesh_obj.substr(start, end == std::string::npos ? end : end - start);
        // Matches reference: empty tokens survive (Python split keeps them), digits and the
        // generator names are dropped (spec 5.7).
        if (!all_digits(token) && token != "RichDreamer" && token != "InstantMesh") {
            if (!first) words += ' ';
            words += token;
            first = false;
        }
        if (end == std::string::npos) break;
        start = end + 1;
    }
    return words;
}

std::string textured_prompt(const std::string& mesh_obj, const std::string& texture) {
    return object_words(mesh_obj) + " with " + texture_description(texture) + " texture" + kPromptSuffix;
}

MultiPartPrompt multi_part_prompt(const std::string& mesh_obj, const std::string& texture_a,
                                  const std::string& texture_b) {
    struct Entry {
        const char* mesh;
        const char* description;
        const char* part_a;
        const char* part_b;
        int token_a;
        int token_b;
    };
    // Matches reference: the seven hard-coded multi-part meshes (spec 5.7).
    static const Entry entries[] = {
        {"a_table_tennis_racket", "a racket with red face and wooden handle", "face", "handle", 5, 8},
        {"a_gold_goat_sculpture", "a goat sculpture with gold goat and black base", "goat", "base", 6, 9},
        {"a_potted_cactus", "a cactus in a pot", "cactus", "pot", 2, 5},
        {"lamp1", "a lamp with white lampshade and wooden base", "lampshade", "base", 5, 8},
        {"lamp3", "a lamp with beige lampshade and wooden base", "lampshade", "base", 5, 8},
        {"a_cactus_in_a_pot_2", "a cactus in a pot", "cactus", "pot", 2, 5},
        {"a_cactus_in_a_pot_3", "a cactus in a pot", "cactus", "pot", 2, 5},
    };
    const std::string desc_a = texture_description(texture_a);
    const std::string desc_b = texture_description(texture_b);
    for (const Entry& e : entries) {
        if (mesh_obj != e.mesh) continue;
        MultiPartPrompt result;
        result.prompt = std::string(e.description) + ", " + e.part_a + " with " + desc_a + " texture, " +
                        e.part_b + " with " + desc_b + " texture" + kPromptSuffix;
        result.part_a_token = e.token_a;
        result.part_b_token = e.token_b;
        return result;
    }
    throw_error(
        "mesh '{}' has no multi-part description (the reference knows a_table_tennis_racket, "
        "a_gold_goat_sculpture, a_potted_cactus, lamp1, lamp3, a_cactus_in_a_pot_2, "
        "a_cactus_in_a_pot_3)",
        mesh_obj);
}

}  // namespace tdf

#pragma once
/// The real diffusion models, out of process: for every guidance call, tdf writes a folder with
/// `request.json` and the input images, runs a user-configured program, and reads back the
/// refined images the program wrote. The protocol (version "tdf-guidance/1") is specified in
/// docs/guidance-protocol.md, with recipes for stable-diffusion.cpp and diffusers.
///
/// Call folder `<work_folder>/<kind>_<iteration, 5 digits>_<call counter, 4 digits>/`:
///   request.json            the request (below)
///   input_<k>.png           visual: the colour render, 8-bit RGB
///                           tactile: (n + 1) / 2 as 16-bit RGB (the reference's model input)
///   input_<k>.exr           tactile only: the raw view-space normals, float
///   control_<k>.png         visual only: BAE control image, 16-bit RGB (to_bae_control())
///   mask_<k>.png            coverage, 8-bit gray
///   refined_<k>.png | .exr  written by the program: see request.json "outputs"
///   stdout.txt, stderr.txt  the program's output streams
/// k = 0..N-1. PNG values are value / (2^bits - 1); 8-bit files are rounded, not truncated.
/// Refined files: visual PNG (RGB or RGBA; alpha ignored) read as value / max; tactile PNG read
/// as 2 * value - 1, or an EXR (preferred when both exist) read as raw vectors. Size must equal
/// the input's. Visual results get white background where the mask is exactly 0 (spec 5.4);
/// tactile results are used as written (the reference does not mask them, spec 5.5).
///
/// Failures throw tdf::Error naming the command and the file: the program cannot be started,
/// exits non-zero (with the last lines of its stderr), is killed by a signal, runs past the
/// timeout (its whole process group is killed with SIGKILL), or leaves an output missing,
/// unreadable, of the wrong size or channel count, or non-finite. The call folder is kept
/// after a failure whatever `keep_files` says, so the user can inspect it.
#include <tdf/guidance/guidance_backend.h>

#include <string>
#include <vector>

namespace tdf {

class ExternalBackend final : public GuidanceBackend {
public:
    static constexpr const char* kName = "external";

    struct Options {
        /// "command": the program and its arguments, either a JSON array of strings (argv, no
        /// shell) or one string split at spaces (no quoting; use the array form for arguments
        /// with spaces). In every argument "{request}" is replaced by the absolute path of
        /// request.json and "{folder}" by the absolute call folder; when no argument contains
        /// either, the request path is appended as the last argument. Required.
        std::vector<std::string> command;
        /// "shell": run the string form through `/bin/sh -c` instead (pipes, redirections,
        /// environment variables). The placeholders are replaced in the string first.
        bool shell = false;
        /// "timeout_seconds": wall-clock limit per call (> 0).
        double timeout_seconds = 600.0;
        /// "work_folder": parent of the call folders; "" = `<system temp>/tdf-guidance-<pid>`.
        std::string work_folder;
        /// "keep_files": keep each call folder after a successful call (always kept on failure).
        bool keep_files = false;
        /// "kinds": the request kinds the program handles, subset of ["visual", "tactile"].
        std::vector<GuidanceKind> kinds = {GuidanceKind::Visual, GuidanceKind::Tactile};

        /// Reads the keys above; throws tdf::Error for unknown keys or bad values.
        static Options from_json(const Json& config);
    };

    explicit ExternalBackend(Options options);
    /// Removes the default temporary work folder when it is empty (kept call folders stay).
    ~ExternalBackend() override;

    std::string name() const override { return kName; }
    bool supports(GuidanceKind kind) const override;
    /// Runs one call as described above.
    GuidanceResult refine(const GuidanceRequest& request) override;

    /// The folder of the most recent call (kept or removed per keep_files), for messages.
    const std::string& last_call_folder() const { return m_last_call_folder; }
    const Options& options() const { return m_options; }

private:
    Options m_options;
    std::string m_work_folder;
    bool m_temporary_work_folder = false;
    int m_calls = 0;
    std::string m_last_call_folder;
};

/// Writes request.json and the input files of `request` into `folder` (created if missing) and
/// returns the JSON written. Exposed for tests and for tools that prepare calls offline.
Json write_guidance_request(const std::string& folder, const GuidanceRequest& request);

/// Reads the refined images named in `request_json` ("outputs") from `folder`, validates them
/// against `request` and applies the background rule above. `command` is named in errors.
GuidanceResult read_guidance_outputs(const std::string& folder, const Json& request_json,
                                     const GuidanceRequest& request, const std::string& command);

}  // namespace tdf

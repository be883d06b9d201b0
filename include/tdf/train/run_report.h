#pragma once
/// `<name>_report.html` of a `tdf optimize` run (tdf/report/run_report.h is the page writer):
/// renders the turntables the page compares and gathers the run's files into a RunReport.
#include <tdf/render/scene_assets.h>
#include <tdf/report/run_report.h>
#include <tdf/train/run_config.h>

#include <string>

namespace tdf {

/// Reads what a finished run left in `folder` (`<name>_*.json`, `_losses.jsonl`, maps, .glb,
/// `turntable*/` frames) into a RunReport. Only files that exist are listed.
RunReport collect_run_report(const std::string& folder, const std::string& name,
                             const std::string& scene_path, const TriangleMesh& mesh,
                             const RunConfig& config);

/// Renders the input (the scene's own textures, `turntable_input/`) and the after-matching asset
/// (the exported `<name>_initialized` maps, `turntable_initialized/`) with the cameras of
/// `turntable/`, then writes `<folder>/<name>_report.html`. Nothing is rendered when
/// export.turntable_views is 0.
void write_optimize_report(const std::string& folder, const std::string& name, const std::string& scene_path,
                           const SceneAssets& assets, const RunConfig& config);

}  // namespace tdf

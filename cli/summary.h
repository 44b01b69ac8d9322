// Where each statistic becomes report text, once: every function here records one struct's
// figures into a Report, and the printed summaries are templates over the same Report.
#pragma once

#include "cli/report.h"
#include "prtsub/prt/bake.h"

namespace prtsub {

void record(Report& r, const MeshDefects& defects);
void record(Report& r, const RefineStats& stats);
//! The fit's keys; `method` decides which apply.
void record(Report& r, const FitStats& stats, const FitOptions& options, const FitData& data, int sample_rays);
//! Everything a bake reports: its options, the meshes' counts, each stage's time and rays.
void record(Report& r, const BakeResult& result, const BakeOptions& options);

//! The bake summary (stdout), from a record made by the functions above.
void print_bake_summary(const Report& r);

}  // namespace prtsub

// The relighting viewer's page (viewer/, docs/viewer.md): one self-contained HTML file, the
// asset embedded as a GLB, the bundle of viewer/dist/viewer.js inlined. `prtsub view` writes it
// and `prtsub compare` embeds one in its report.
#pragma once

#include <string>
#include <vector>

#include "prtsub/prt/asset.h"
#include "prtsub/prt/ray_scene.h"
#include "prtsub/prt/transfer.h"

namespace prtsub {

//! The error view's data: points on a regular grid of barycentrics inside every asset triangle
//! (n segments an edge), triangle by triangle, row i (weight i/n on the second corner) by column
//! j (j/n on the third), with reference transfer traced there. The page rebuilds the same grid
//! with the asset's transfer interpolated as a GPU interpolates it; only the reference travels.
struct ErrorView {
  int segments = 1;
  RowMatrixX3d positions, normals;  //!< #P by 3 (normals interpolated and normalised)
  RowMatrixXd reference;            //!< #P by the asset's coefficients
  int rays = 0;
};

//! The grid, n the largest of 1..8 with F·n² ≤ target_triangles (at least 1), and the reference
//! traced at it on `source` (the mesh the asset was baked from) with `options` (its order is the
//! asset's). \throw EmbreeError
ErrorView trace_error_view(const Asset& asset, const RayScene& source, TransferOptions options, size_t target_triangles = 20000);

struct ViewerPageOptions {
  std::string name;  //!< shown in the page's title and panel (escaped)
  const ErrorView* error = nullptr;  //!< null leaves the error view off
  //! random lights the page offers (the library's generator, so they match `--light random:S`)
  std::vector<uint64_t> random_seeds = {1, 2, 3, 4, 5, 6, 7, 8};
};

//! The page for `asset`. Text from files reaches it only escaped: the name through html_escape
//! and json_quote, the asset and the reference as base64. \throw InputError as write_asset
std::string viewer_page(const Asset& asset, const ViewerPageOptions& options);

//! The page's data alone: the JSON object the viewer reads from its prtsub-data element (for
//! compare's report, which embeds the viewer in an iframe of its own).
std::string viewer_data_json(const Asset& asset, const ViewerPageOptions& options);

}  // namespace prtsub

// The PRT asset: a binary little-endian PLY with per-vertex transfer. docs/asset_format.md
// is the contract with consumers.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "prtsub/prt/albedo.h"
#include "prtsub/prt/output_file.h"
#include "prtsub/prt/sg_basis.h"
#include "prtsub/prt/sh.h"
#include "prtsub/subdiv/mesh.h"

namespace prtsub {

using Metadata = std::vector<std::pair<std::string, std::string>>;

//! What an asset's vertices carry: SH transfer (t0..t{N²-1}) or ambient occlusion (ao).
enum class AssetSignal { Transfer, Ao };
AssetSignal parse_asset_signal(const std::string& name);  //!< transfer, ao \throw InputError
const char* asset_signal_name(AssetSignal s);

//! ao = t0 · 2/√π: ambient occlusion (1/π)∫V max(n·ω,0) dω is order-1 transfer over y_0 = 1/(2√π),
//! divided by π. prtsub bakes AO as order-1 transfer and converts on writing and reading.
constexpr double kAoPerT0 = 1.1283791670955126;

//! An asset as read back: render vertices with their transfer.
struct Asset {
  RowMatrixX3d positions;             //!< #V by 3
  RowMatrixX3d normals;               //!< #V by 3
  RowMatrixX2d uv;                    //!< #V by 2, or no rows when the asset has none
  //! #V by N², or #V by 3·N² (channels 3: red, green, blue blocks). For a spherical-Gaussian
  //! asset, the lobes' SH equivalent at `order` (sg_to_sh): exact for every light of that order,
  //! so every SH consumer relights it as it is
  RowMatrixXd transfer;
  //! A spherical-Gaussian asset's own values (metadata `sg_lobes`): #V by lobes, c_k of
  //! T(ω) ≈ Σ c_k G_k(ω) over sg_basis(lobes); no rows for SH. What the file stores.
  RowMatrixXd sg;
  RowMatrixX3d albedo;                //!< #V by 3 linear albedo, or no rows (a grey bake records none)
  std::vector<Triangle> triangles;    //!< #F
  std::vector<uint32_t> source_face;  //!< #F
  Metadata metadata;                  //!< "key value" comment lines, in order
  int order = 0;                      //!< 1 for AO assets; sg_shading_order for SG assets
  int channels = 1;                   //!< 3: RGB transfer (a coloured albedo that bounced)
  AssetSignal signal = AssetSignal::Transfer;  //!< ao assets are read into transfer as t0 = ao / kAoPerT0
};

//! The asset's mesh, to write it again (in another format, say): one position per render
//! vertex (nothing welded), its normals, UVs, triangles and source faces.
Mesh asset_mesh(const Asset& asset);

//! The asset write_asset would write, without the file: render-vertex positions, the mesh's
//! normals, UVs, triangles and source faces, the values (order-1 transfer for AO).
//! \param albedo #V by 3 linear albedo per vertex, or no rows
Asset make_asset(const Mesh& mesh, const RowMatrixXd& transfer, const Metadata& metadata, AssetSignal signal = AssetSignal::Transfer,
                 const RowMatrixX3d& albedo = RowMatrixX3d());

//! AO: clamps order-1 transfer into the AO range [0, 1]·(√π/2); returns how many values moved.
size_t clamp_ao(RowMatrixXd& t0);

//! The comment lines stating the SH convention, written into every transfer asset.
Metadata sh_convention_metadata(int order);

//! The comment lines of a spherical-Gaussian transfer asset (docs/sh_convention.md, "Spherical
//! Gaussians"): the lobe count, sharpness and axes, how the values were encoded, how they relight.
Metadata sg_convention_metadata(const SgBasis& basis, bool non_negative);

//! The lobe count a metadata's `sg_lobes` line gives, or 0 (SH) without one.
//! \throw InputError naming `path` unless it is a count of kMinSgLobes to kMaxSgAssetLobes
int metadata_lobes(const Metadata& metadata, const std::string& path);

//! Makes `a` a spherical-Gaussian asset of these lobe coefficients (#V by N, N a lobe count
//! metadata_lobes accepts): sg, order (sg_shading_order) and transfer (their SH equivalent).
void set_asset_lobes(Asset& a, const RowMatrixXd& lobes);

//! The values as the file stores them: the lobes of an SG asset, else the transfer.
const RowMatrixXd& stored_values(const Asset& asset);

//! The comment lines of an AO asset: what ao means.
Metadata ao_metadata();

//! The checks every asset writer makes before writing anything: the transfer's shape, finite
//! values that fit in float, UVs for every vertex; with lobes > 0, #V by lobes grey transfer.
//! \throw InputError naming `path`
void check_asset_input(const std::string& path, const Mesh& mesh, const RowMatrixXd& transfer, AssetSignal signal,
                       const RowMatrixX3d& albedo = RowMatrixX3d(), int lobes = 0);

//! Writes mesh + transfer to `path` through a temporary file renamed into place, so a failed
//! run leaves nothing behind.
//! \param transfer #V by N², V = mesh.num_vertices(), or #V by 3·N² for RGB transfer (written as
//!        r_t*, g_t*, b_t*); for AO #V by 1 order-1 transfer, written as the property ao = t0 · kAoPerT0;
//!        when metadata has `sg_lobes` N (sg_convention_metadata), #V by N lobe coefficients
//! \param albedo #V by 3 linear albedo in [0, 1], written as albedo_r, albedo_g, albedo_b; or no rows
//! \throw InputError if transfer holds NaN/Inf or has the wrong shape, IoError if writing fails
void write_asset(const std::string& path, const Mesh& mesh, const RowMatrixXd& transfer,
                 const Metadata& metadata, AssetSignal signal = AssetSignal::Transfer, const RowMatrixX3d& albedo = RowMatrixX3d());

//! What an asset baked with bounces folded into its transfer (metadata `bounces`).
struct AssetBounces {
  int bounces = 0;  //!< 0: shadowed transfer only
  double albedo = 0.8;  //!< a grey albedo's value
  //! A coloured albedo (the `albedo` metadata: R,G,B, vertex colours or a map): the bounces then
  //! carry it, and `albedo` above is unused
  bool coloured = false;
  AlbedoSpec spec;  //!< what the `albedo` metadata line says (a grey constant when absent)
};
//! \throw InputError naming `path` if the metadata is there but not as bake writes it
AssetBounces asset_bounces(const Asset& asset, const std::string& path);

//! Reads an asset and checks it: sizes consistent, indices in range, no NaN/Inf. A glTF asset
//! (docs/asset_format.md, "glTF"), told apart by its bytes, is read by parse_gltf_asset.
//! \throw InputError naming the file and the first problem found
Asset read_asset(const std::string& path);

//! The same from the file's bytes (`path` only names it in messages).
Asset parse_asset(const std::string& bytes, const std::string& path);


}  // namespace prtsub

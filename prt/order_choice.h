// --order auto: the lowest SH order a scene needs, chosen from a pilot subset of its vertices.
#pragma once

#include <vector>

#include "prtsub/prt/ray_scene.h"
#include "prtsub/prt/transfer.h"

namespace prtsub {

struct OrderChoiceOptions {
  int max_order = 8;  //!< the highest order considered (and traced by the pilot), 2..10
  //! The truncation error to stay under, in percent of ‖t_unshadowed‖ (eval's unit); 0: the
  //! bake's own noise at each order (what more bands would add is below what the rays resolve)
  double tolerance_percent = 0;
  size_t pilot_points = 2000;  //!< vertices the pilot traces (evenly spread by index; all if fewer)
  //! The light the asset will be relit with, as its power per band P_l (l < max_order): errors
  //! are then the RMS radiance error under that light turned any way, relative to an unshadowed
  //! point's radiance under it, and band l counts with weight P_l / (2l + 1). Empty: every band
  //! weighs 1, which is eval's metric (the worst unit-power light: a sun-like light's spectrum).
  std::vector<double> band_power;
};

struct OrderChoice {
  int order = 0;  //!< the choice; 0 when no choice was made
  //! per order N = 1..max_order (index N − 1), in percent of ‖t_unshadowed‖, RMS over the pilot:
  std::vector<double> truncation_percent;  //!< what order N leaves out (bands N..max_order − 1; 0 at max_order: not seen)
  std::vector<double> noise_percent;       //!< the noise of an order-N bake's values at its rays
  double tolerance_percent = 0;            //!< what the choice stayed under (the noise at `order` by default)
  bool reached = true;                     //!< false: no order up to max_order got there; max_order chosen
  size_t points = 0;
  uint64_t rays = 0;
  double seconds = 0;
};

//! Traces the pilot twice at max_order with independent seeds (the bake's rays and threads):
//! their mean's coefficients, less their estimated variance, give the energy of every band, and
//! their difference the noise. Truncation at order N is the RMS over points of ‖t_{bands ≥ N}‖,
//! the worst unit-power light's radiance error from dropping those bands (eval's metric), or with
//! band_power the error under that light turned any way. The
//! lowest N below max_order whose truncation is at most the tolerance is chosen (max_order, with
//! `reached` false, when none is). The same for any thread count.
//! \param mesh_points, normals, offsets the mesh's vertices (#V by 3 each), as the bake traces them
//! \throw InputError for options out of range, EmbreeError
OrderChoice choose_order(const RayScene& scene, const RowMatrixX3d& mesh_points, const RowMatrixX3d& normals, const RowMatrixX3d& offsets,
                         const TransferOptions& transfer, const OrderChoiceOptions& options);

}  // namespace prtsub

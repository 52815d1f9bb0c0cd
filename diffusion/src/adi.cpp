// The ADI passes on a LinkField: the engine of detail/adi_impl.hpp reading the links from
// the field's planes and its record of active tiles.
#include "tridiff/diffusion/adi.hpp"

#include <algorithm>
#include <vector>

namespace tridiff {
namespace {

using adi_detail::Direction;
using adi_detail::PlaneStack;

class LinkFieldSource {
 public:
  explicit LinkFieldSource(const LinkField& links) : links_(links) {}

  void activity(Direction direction, std::ptrdiff_t band, std::vector<std::uint8_t>& active) const {
    const bool rows = direction == Direction::Rows;
    active.resize(rows ? links_.tiles_x() : links_.tiles_y());
    for (std::ptrdiff_t t = 0; t < std::ptrdiff_t(active.size()); ++t)
      active[t] = rows ? links_.horizontal_active(t, band) : links_.vertical_active(band, t);
  }
  template <int W>
  void row_link_lanes(std::ptrdiff_t y0, std::ptrdiff_t count, std::ptrdiff_t x0,
                      std::ptrdiff_t columns, const float* zero_row, float* lanes) const {
    const ConstPlane h = links_.horizontal();
    const float* rows[W];
    adi_detail::band_rows<W>(h.row(y0), h.pitch(), count, zero_row, rows);
    detail::gather_into_lanes<float, W>(rows, x0, columns, lanes, h.width());
  }
  void prefetch_column(std::ptrdiff_t y, std::ptrdiff_t x0, std::ptrdiff_t count) const {
    adi_detail::prefetch_span(links_.vertical().row(y) + x0, count);
  }
  void column_links(std::ptrdiff_t y0, std::ptrdiff_t rows, std::ptrdiff_t x0, std::ptrdiff_t count,
                    std::ptrdiff_t lanes, float* out) const {
    for (std::ptrdiff_t r = 0; r < rows; ++r) {
      const float* row = links_.vertical().row(y0 + r);
      std::copy(row + x0, row + x0 + count, out + r * lanes);
      std::fill(out + r * lanes + count, out + (r + 1) * lanes, 0.f);
    }
  }

 private:
  const LinkField& links_;
};

void require_links_fit(std::ptrdiff_t width, std::ptrdiff_t height, const LinkField& beta) {
  adi_detail::require_same_size(width, height, beta.horizontal(), "beta");
}

PlaneStack<float> stack_of(Plane p) { return {p.data(), p.width(), p.height(), p.pitch(), 0, 1}; }
PlaneStack<const float> stack_of(ConstPlane p) {
  return {p.data(), p.width(), p.height(), p.pitch(), 0, 1};
}

DiffusionReport one_pass(Direction direction, Plane dst, ConstPlane src, const LinkField& beta,
                         const DiffusionOptions& options) {
  adi_detail::require_same_size(src.width(), src.height(), dst, "dst");
  require_links_fit(src.width(), src.height(), beta);
  return adi_detail::run_pass(direction, stack_of(dst), stack_of(src), LinkFieldSource(beta),
                              options);
}

}  // namespace

DiffusionReport diffuse_rows(Plane dst, ConstPlane src, const LinkField& beta,
                             const DiffusionOptions& options) {
  return one_pass(Direction::Rows, dst, src, beta, options);
}

DiffusionReport diffuse_columns(Plane dst, ConstPlane src, const LinkField& beta,
                                const DiffusionOptions& options) {
  return one_pass(Direction::Columns, dst, src, beta, options);
}

DiffusionReport diffuse_adi(Image& dst, const Image& src, const LinkField& beta,
                            const DiffusionOptions& options) {
  require_links_fit(src.width(), src.height(), beta);
  return adi_detail::run_adi(dst, src, LinkFieldSource(beta), options);
}

}  // namespace tridiff

/// \file grid_cells_sse2.h
/// The grid cell of four points at once (SSE2), shared by the simple grid's and the hierarchical
/// detector's binning: column = trunc((x - origin) * inv), row = trunc((y - origin) * inv), and
/// the flat index row * stride + column + offset when 0 <= column, row < side and |h| <= max_abs
/// (h: the height the caller bins on), else -1. The same float operations, in the same order, as
/// the scalar loops beside each caller (subtract, multiply, ordered comparisons, truncation), so
/// the same cells. Header-only: the callers inline it into their loops.
#pragma once

#if defined(__SSE2__)
#include <emmintrin.h>
#include <xmmintrin.h>

namespace urban_detection {
namespace core {

class GridCellsSse2 {
 public:
  GridCellsSse2(float origin, float inv_cell, float side, float max_abs, int stride, int offset)
      : origin_(_mm_set1_ps(origin)),
        inv_(_mm_set1_ps(inv_cell)),
        side_(_mm_set1_ps(side)),
        max_abs_(_mm_set1_ps(max_abs)),
        stride_(_mm_set1_epi32(stride)),
        offset_(_mm_set1_epi32(offset)) {}

  /// Cells of the four points (x, y, h) (one lane each); `valid` receives all bits set in the
  /// lanes that have a cell and zero in the others (whose cell is -1).
  __m128i cells(__m128 x, __m128 y, __m128 h, __m128i* valid) const {
    const __m128 zero = _mm_setzero_ps();
    const __m128 fc = _mm_mul_ps(_mm_sub_ps(x, origin_), inv_);
    const __m128 fr = _mm_mul_ps(_mm_sub_ps(y, origin_), inv_);
    const __m128 ok =
        _mm_and_ps(_mm_and_ps(_mm_and_ps(_mm_cmpge_ps(fc, zero), _mm_cmplt_ps(fc, side_)),
                              _mm_and_ps(_mm_cmpge_ps(fr, zero), _mm_cmplt_ps(fr, side_))),
                   _mm_cmple_ps(_mm_andnot_ps(_mm_set1_ps(-0.0f), h), max_abs_));
    *valid = _mm_castps_si128(ok);
    // row * stride in 32-bit lanes with SSE2 only (no pmulld): two 32x32->64 products (even
    // lanes, then odd ones shifted down), their low halves interleaved back.
    const __m128i r = _mm_cvttps_epi32(fr), c = _mm_cvttps_epi32(fc);
    const __m128i even = _mm_mul_epu32(r, stride_);
    const __m128i odd = _mm_mul_epu32(_mm_srli_epi64(r, 32), stride_);
    const __m128i prod = _mm_unpacklo_epi32(_mm_shuffle_epi32(even, _MM_SHUFFLE(0, 0, 2, 0)),
                                            _mm_shuffle_epi32(odd, _MM_SHUFFLE(0, 0, 2, 0)));
    const __m128i cell = _mm_add_epi32(_mm_add_epi32(prod, c), offset_);
    return _mm_or_si128(_mm_and_si128(*valid, cell), _mm_andnot_si128(*valid, _mm_set1_epi32(-1)));
  }

 private:
  __m128 origin_, inv_, side_, max_abs_;
  __m128i stride_, offset_;
};

}  // namespace core
}  // namespace urban_detection
#endif

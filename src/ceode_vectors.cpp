// The vectors a memory creates for itself (CloneVector). A serial vector from N_VClone is four
// allocations (the vector, its operation table, its content, its data) and a table filled entry
// by entry, about 1 300 instructions: a start clones 20 to 46 of them, as much work as a hundred
// steps of a small problem. A serial template here gives one allocation that holds all four, the
// table copied whole. Its own clone, empty clone and destroy operations keep that layout, so the
// vector stays an NVECTOR_SERIAL vector for every caller: SUNDIALS' solvers and the user's
// callbacks may clone and destroy it as any other. Other vectors are N_VClone's.
#include <nvector/nvector_serial.h>

#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <new>

#include "ceode_impl.hpp"

namespace ceode {

namespace {

// One allocation: the vector, its operation table, its content, then its data on a boundary of
// kDataAlign bytes from the allocation's start (malloc's own alignment or better).
constexpr std::size_t kDataAlign = 64;
struct SerialBlock {
  _generic_N_Vector vec;
  _generic_N_Vector_Ops ops;
  _N_VectorContent_Serial content;
};
constexpr std::size_t kDataOffset =
    (sizeof(SerialBlock) + kDataAlign - 1) / kDataAlign * kDataAlign;
// The vector is the allocation's start: freeing it frees the block.
static_assert(offsetof(SerialBlock, vec) == 0, "the vector opens its block");

void DestroyBlock(N_Vector v) { std::free(v); }
N_Vector CloneBlock(N_Vector w);

// A block like w's, with length entries of data (none for an empty clone).
N_Vector NewBlock(N_Vector w, bool data) {
  const sunindextype length = NV_LENGTH_S(w);
  const std::size_t bytes =
      kDataOffset + (data ? static_cast<std::size_t>(length) * sizeof(sunrealtype) : 0);
  auto* raw = static_cast<unsigned char*>(std::malloc(bytes));
  if (raw == nullptr) return nullptr;
  auto* b = new (raw) SerialBlock;
  std::memcpy(&b->ops, w->ops, sizeof b->ops);
  b->ops.nvclone = CloneBlock;
  b->ops.nvcloneempty = [](N_Vector u) { return NewBlock(u, false); };
  b->ops.nvdestroy = DestroyBlock;
  b->content.length = length;
  b->content.own_data = SUNFALSE;  // the data lie in the block: DestroyBlock frees them with it
  b->content.data =
      data && length > 0 ? reinterpret_cast<sunrealtype*>(raw + kDataOffset) : nullptr;
  b->vec.content = &b->content;
  b->vec.ops = &b->ops;
  b->vec.sunctx = w->sunctx;
  return &b->vec;
}

N_Vector CloneBlock(N_Vector w) { return NewBlock(w, true); }

}  // namespace

N_Vector CloneVector(N_Vector tmpl) {
  if (tmpl == nullptr || tmpl->ops == nullptr) return nullptr;
  if (N_VGetVectorID(tmpl) != SUNDIALS_NVEC_SERIAL || tmpl->ops->nvclone == nullptr) {
    return N_VClone(tmpl);
  }
  return NewBlock(tmpl, true);
}

bool CloneMissing(N_Vector* v, N_Vector tmpl) {
  if (*v == nullptr) *v = CloneVector(tmpl);
  return *v != nullptr;
}

}  // namespace ceode

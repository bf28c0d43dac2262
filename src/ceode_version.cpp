// The library's version (CEodeGetVersion, CEodeGetVersionNumber), as SUNDIALS reports its own:
// the values compiled into libceode from ceode_config.h, so a program can compare them with the
// CEODE_VERSION_* macros of the headers it was compiled with. No memory, so no error message:
// a bad argument returns CE_ILL_INPUT, as the other memory-less lookups (CEodeGetMethodParams) do.
#include <cstring>

#include "ceode/ceode.h"

namespace {

// Copies text with its '\0' into out[0..len-1]; false (out untouched) when it does not fit.
bool CopyString(const char* text, char* out, int len) {
  if (out == nullptr || len <= 0) return false;
  const std::size_t n = std::strlen(text);
  if (n >= static_cast<std::size_t>(len)) return false;
  std::memcpy(out, text, n + 1);
  return true;
}

}  // namespace

int CEodeGetVersion(char* version, int len) {
  return CopyString(CEODE_VERSION, version, len) ? CE_SUCCESS : CE_ILL_INPUT;
}

int CEodeGetVersionNumber(int* major, int* minor, int* patch, char* label, int len) {
  if (major == nullptr || minor == nullptr || patch == nullptr) return CE_ILL_INPUT;
  if (!CopyString(CEODE_VERSION_LABEL, label, len)) return CE_ILL_INPUT;
  *major = CEODE_VERSION_MAJOR;
  *minor = CEODE_VERSION_MINOR;
  *patch = CEODE_VERSION_PATCH;
  return CE_SUCCESS;
}

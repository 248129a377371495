// xxHash used header-only (XXH_INLINE_ALL), so the GPU machine needs only the carried headers.
#pragma once
#define XXH_INLINE_ALL
#include <xxhash.h>

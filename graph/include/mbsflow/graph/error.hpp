#pragma once
// Kept for embedding programs written against 0.1: the error hierarchy lives in the base
// target now (mbsflow/error.hpp), linked by every layer.
#include "mbsflow/error.hpp"

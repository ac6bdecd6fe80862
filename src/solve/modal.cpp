#include "screwfem/solve/statics.h"

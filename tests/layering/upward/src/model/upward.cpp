// A model-layer file that includes the assembly: the layering check must reject it.
#include "screwfem/model/model.h"
#include "screwfem/assemble/assemble.h"

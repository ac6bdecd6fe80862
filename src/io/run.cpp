#include "screwfem/io/run.h"

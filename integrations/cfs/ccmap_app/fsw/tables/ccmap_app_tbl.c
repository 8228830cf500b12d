/* Default parameter table of ccmap_app: the library's CADRE defaults, the 80 ms cycle budget. */
#include "cfe_tbl_filedef.h"
#include "ccmap_app_tbl.h"

CCMAP_APP_ParamTable_t CCMAP_APP_Params = {
    .FinestCellWidthM  = 0.04f,
    .WeightLimit       = 1000.0f,
    .CoverageTau       = 0.8f,
    .MinWeight         = 5.0f,
    .ObstacleFraction  = 0.75f,
    .MaxInclination    = 0.36397023f, /* tan(20 deg) */
    .OutlierGateSigma  = 3.0f,
    .FramePointBudget  = 0,
    .FrameTimeBudgetUs = 0,
    .FreeSpaceRays     = 256.0f,
    .CycleBudgetUs     = 80000,
};

CFE_TBL_FILEDEF(CCMAP_APP_Params, CCMAP_APP.Params, ccmap parameters, ccmap_app_tbl.tbl)

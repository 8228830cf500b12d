/* ccmap_app parameter table ("CCMAP_APP.Params", file ccmap_app_tbl.tbl): the operator's tunables.
 * The app lays them over the library's defaults for the finest cell width
 * (ccmap_default_params_for_width); the table's validation function is the library's own
 * parameter validation, so a value the library would refuse never becomes active. Units and ranges
 * are those of ccmap_params (include/ccmap/ccmap.h). */
#ifndef CCMAP_APP_TBL_H
#define CCMAP_APP_TBL_H

#include "common_types.h"

typedef struct
{
    float  FinestCellWidthM;  /* layer 0 width, m (CADRE: 0.04) */
    float  WeightLimit;       /* W_l */
    float  CoverageTau;       /* (0, 1], paper 0.8 */
    float  MinWeight;
    float  ObstacleFraction;
    float  MaxInclination;    /* dz/dxy */
    float  OutlierGateSigma;  /* 0 (off) or 1..100 */
    uint32 FramePointBudget;  /* points per frame, 0: all */
    uint32 FrameTimeBudgetUs; /* library time budget per frame, 0: none */
    float  FreeSpaceRays;     /* lines of sight per frame, 0..65535 */
    uint32 CycleBudgetUs;     /* the app's budget for one frame's handling (HK BudgetOverruns) */
} CCMAP_APP_ParamTable_t;

#endif

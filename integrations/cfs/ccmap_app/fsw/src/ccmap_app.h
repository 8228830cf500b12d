/* ccmap_app: the ccmap terrain map as a cFS application. Its state (the map included) is in
 * static storage; nothing is allocated. */
#ifndef CCMAP_APP_H
#define CCMAP_APP_H

#include "cfe.h"
#include "ccmap/ccmap.h"
#include "ccmap_app_msgids.h"
#include "ccmap_app_msg.h"
#include "ccmap_app_fcncodes.h"
#include "ccmap_app_tbl.h"
#include "ccmap_app_platform_cfg.h"
#include "ccmap_frames.h"

#define CCMAP_APP_VERSION "1.0.0"
/* The product: the 8 cm layer's 64 x 64 window (5.12 m), each cell the stack's answer. */
#define CCMAP_APP_PRODUCT_LAYER 1
#define CCMAP_APP_PRODUCT_CELLS (64u * 64u)

typedef struct
{
    uint32 RunStatus;
    CFE_SB_PipeId_t   CommandPipe;
    CFE_TBL_Handle_t  TblHandle;
    CCMAP_APP_ParamTable_t Table; /* the active table, copied at each update */
    ccmap_map        *Map;
    ccmap_product_buffers Products;
    float             LastPose[3]; /* the last frame's sensor position (map frame, m): the product's pose */
    CCMAP_APP_HkTlm_t      HkTlm;      /* counters live in its payload */
    CCMAP_APP_ProductTlm_t ProductTlm;
} CCMAP_APP_Data_t;

extern CCMAP_APP_Data_t CCMAP_APP_Data;

void         CCMAP_APP_Main(void);
CFE_Status_t CCMAP_APP_Init(void);
/* The table's validation callback: the library's own check of the parameters it gives. */
CFE_Status_t CCMAP_APP_ValidateTable(void *TblData);
/* Table services' housekeeping: validations, loads; applies an updated table to the map. */
void CCMAP_APP_ManageTable(void);
/* The library's parameters from a table (the library's defaults for its cell width, overlaid). */
ccmap_status CCMAP_APP_ParamsFromTable(const CCMAP_APP_ParamTable_t *Tbl, ccmap_params *Params);
/* Maps the frame a FRAME_READY message names (ccmap_app_frame.c). */
void CCMAP_APP_FrameReady(const CFE_SB_Buffer_t *SBBufPtr);

#endif

/* ccmap_app: entry point, initialisation and the parameter table. */
#include <string.h>

#include "ccmap_app.h"
#include "ccmap_app_dispatch.h"
#include "ccmap_app_eventids.h"

CCMAP_APP_Data_t CCMAP_APP_Data;

/* The map, its product buffers: static storage, sized by the library's constants. */
static ccmap_cadre_storage CCMAP_APP_MapStorage;
static uint32 CCMAP_APP_ProductStorage[CCMAP_PRODUCT_BUFFERS_STORAGE_SIZE(CCMAP_APP_PRODUCT_CELLS) / 4u];

/* The library's fault hook: contract violations it found become events (it returns a safe value). */
static void CCMAP_APP_FaultHook(void *Context, const char *File, int Line, const char *Expression)
{
    (void)Context;
    CFE_EVS_SendEvent(CCMAP_APP_LIB_FAULT_EID, CFE_EVS_EventType_CRITICAL, "ccmap fault: %s:%d: %s", File, Line,
                      Expression);
}

void CCMAP_APP_Main(void)
{
    CFE_Status_t     Status;
    CFE_SB_Buffer_t *SBBufPtr;

    if (CCMAP_APP_Init() != CFE_SUCCESS)
    {
        CCMAP_APP_Data.RunStatus = CFE_ES_RunStatus_APP_ERROR;
    }
    while (CFE_ES_RunLoop(&CCMAP_APP_Data.RunStatus))
    {
        Status = CFE_SB_ReceiveBuffer(&SBBufPtr, CCMAP_APP_Data.CommandPipe, CFE_SB_PEND_FOREVER);
        if (Status == CFE_SUCCESS)
        {
            CCMAP_APP_TaskPipe(SBBufPtr);
        }
        else
        {
            CFE_EVS_SendEvent(CCMAP_APP_PIPE_ERR_EID, CFE_EVS_EventType_ERROR,
                              "CCMAP: SB pipe read error 0x%08lX, app exits", (unsigned long)Status);
            CCMAP_APP_Data.RunStatus = CFE_ES_RunStatus_APP_ERROR;
        }
    }
    CFE_ES_ExitApp(CCMAP_APP_Data.RunStatus);
}

static CFE_Status_t CCMAP_APP_InitFailed(const char *What, long Code)
{
    CFE_EVS_SendEvent(CCMAP_APP_INIT_ERR_EID, CFE_EVS_EventType_ERROR, "CCMAP: init: %s failed (0x%08lX)", What,
                      (unsigned long)Code);
    return (Code < 0) ? (CFE_Status_t)Code : CFE_STATUS_EXTERNAL_RESOURCE_FAIL;
}

CFE_Status_t CCMAP_APP_Init(void)
{
    CFE_Status_t Status;
    ccmap_status Lib;

    memset(&CCMAP_APP_Data, 0, sizeof(CCMAP_APP_Data));
    CCMAP_APP_Data.RunStatus = CFE_ES_RunStatus_APP_RUN;

    Status = CFE_EVS_Register(NULL, 0, CFE_EVS_EventFilter_BINARY);
    if (Status != CFE_SUCCESS)
    {
        CFE_ES_WriteToSysLog("CCMAP: error registering events, RC = 0x%08lX\n", (unsigned long)Status);
        return Status;
    }
    CFE_MSG_Init(CFE_MSG_PTR(CCMAP_APP_Data.HkTlm.TelemetryHeader), CFE_SB_ValueToMsgId(CCMAP_APP_HK_TLM_MID),
                 sizeof(CCMAP_APP_Data.HkTlm));
    CFE_MSG_Init(CFE_MSG_PTR(CCMAP_APP_Data.ProductTlm.TelemetryHeader),
                 CFE_SB_ValueToMsgId(CCMAP_APP_PRODUCT_TLM_MID), sizeof(CCMAP_APP_Data.ProductTlm));
    (void)ccmap_set_fault_hook(CCMAP_APP_FaultHook, NULL);

    Status = CFE_SB_CreatePipe(&CCMAP_APP_Data.CommandPipe, CCMAP_APP_PIPE_DEPTH, CCMAP_APP_PIPE_NAME);
    if (Status != CFE_SUCCESS)
    {
        return CCMAP_APP_InitFailed("CreatePipe", Status);
    }
    if ((Status = CFE_SB_Subscribe(CFE_SB_ValueToMsgId(CCMAP_APP_SEND_HK_MID), CCMAP_APP_Data.CommandPipe)) !=
            CFE_SUCCESS ||
        (Status = CFE_SB_Subscribe(CFE_SB_ValueToMsgId(CCMAP_APP_CMD_MID), CCMAP_APP_Data.CommandPipe)) !=
            CFE_SUCCESS ||
        (Status = CFE_SB_Subscribe(CFE_SB_ValueToMsgId(CCMAP_FRAMES_READY_MID), CCMAP_APP_Data.CommandPipe)) !=
            CFE_SUCCESS)
    {
        return CCMAP_APP_InitFailed("Subscribe", Status);
    }

    Lib = ccmap_place(&CCMAP_APP_MapStorage, sizeof(CCMAP_APP_MapStorage), CCMAP_PRESET_CADRE, &CCMAP_APP_Data.Map);
    if (Lib == CCMAP_OK)
    {
        Lib = ccmap_product_buffers_init(&CCMAP_APP_Data.Products, CCMAP_APP_ProductStorage,
                                         sizeof(CCMAP_APP_ProductStorage));
    }
    if (Lib != CCMAP_OK)
    {
        return CCMAP_APP_InitFailed(ccmap_status_string(Lib), Lib);
    }

    /* The table: registered with the library's validation, loaded (and validated) from its file,
     * then applied: the first application initialises the map. */
    Status = CFE_TBL_Register(&CCMAP_APP_Data.TblHandle, "Params", sizeof(CCMAP_APP_ParamTable_t),
                              CFE_TBL_OPT_DEFAULT, CCMAP_APP_ValidateTable);
    if (Status != CFE_SUCCESS)
    {
        return CCMAP_APP_InitFailed("CFE_TBL_Register", Status);
    }
    Status = CFE_TBL_Load(CCMAP_APP_Data.TblHandle, CFE_TBL_SRC_FILE, CCMAP_APP_TABLE_FILE);
    if (Status != CFE_SUCCESS)
    {
        return CCMAP_APP_InitFailed("CFE_TBL_Load " CCMAP_APP_TABLE_FILE, Status);
    }
    CCMAP_APP_ManageTable();
    if (!CCMAP_APP_Data.HkTlm.Payload.MapInitialised)
    {
        return CCMAP_APP_InitFailed("map init from the table", CCMAP_APP_Data.HkTlm.Payload.LastStatus);
    }

    CFE_EVS_SendEvent(CCMAP_APP_INIT_INF_EID, CFE_EVS_EventType_INFORMATION,
                      "CCMAP: initialized, version %s, CADRE map %lu bytes, ccmap platform %s", CCMAP_APP_VERSION,
                      (unsigned long)sizeof(CCMAP_APP_MapStorage), ccmap_platform_name());
    return CFE_SUCCESS;
}

ccmap_status CCMAP_APP_ParamsFromTable(const CCMAP_APP_ParamTable_t *Tbl, ccmap_params *Params)
{
    ccmap_status Status = ccmap_default_params_for_width(Tbl->FinestCellWidthM, Params);
    if (Status == CCMAP_OK)
    {
        Params->weight_limit         = Tbl->WeightLimit;
        Params->coverage_tau         = Tbl->CoverageTau;
        Params->min_weight           = Tbl->MinWeight;
        Params->obstacle_fraction    = Tbl->ObstacleFraction;
        Params->max_inclination      = Tbl->MaxInclination;
        Params->outlier_gate_sigma   = Tbl->OutlierGateSigma;
        Params->frame_point_budget   = Tbl->FramePointBudget;
        Params->frame_time_budget_us = Tbl->FrameTimeBudgetUs;
        Params->free_space_rays      = Tbl->FreeSpaceRays;
        Status                       = ccmap_validate_params(CCMAP_PRESET_CADRE, Params);
    }
    return Status;
}

CFE_Status_t CCMAP_APP_ValidateTable(void *TblData)
{
    const CCMAP_APP_ParamTable_t *Tbl = TblData;
    ccmap_params                  Params;
    ccmap_status                  Status = CCMAP_APP_ParamsFromTable(Tbl, &Params);

    if (Status == CCMAP_OK && Tbl->CycleBudgetUs == 0u)
    {
        Status = CCMAP_OUT_OF_RANGE;
    }
    if (Status != CCMAP_OK)
    {
        ++CCMAP_APP_Data.HkTlm.Payload.TableRefusals;
        CFE_EVS_SendEvent(CCMAP_APP_TBL_VAL_ERR_EID, CFE_EVS_EventType_ERROR,
                          "CCMAP: parameter table refused: %s (coverage_tau %.3f, gate %.2f, cell %.4f m, "
                          "cycle budget %lu us)",
                          ccmap_status_string(Status), (double)Tbl->CoverageTau, (double)Tbl->OutlierGateSigma,
                          (double)Tbl->FinestCellWidthM, (unsigned long)Tbl->CycleBudgetUs);
        return CFE_STATUS_VALIDATION_FAILURE;
    }
    return CFE_SUCCESS;
}

/* Applies a validated table: parameters changed in place (the map kept) where the library allows
 * it, else the map re-initialised with them (a new cell width). */
static void CCMAP_APP_ApplyTable(const CCMAP_APP_ParamTable_t *Tbl)
{
    CCMAP_APP_HkTlm_Payload_t *Hk = &CCMAP_APP_Data.HkTlm.Payload;
    ccmap_params               Params;
    uint32_t                   NeedsReinit = 0;
    ccmap_status               Status      = CCMAP_APP_ParamsFromTable(Tbl, &Params);
    bool                       Kept        = false;

    if (Status == CCMAP_OK && Hk->MapInitialised)
    {
        Status = ccmap_set_params(CCMAP_APP_Data.Map, &Params, &NeedsReinit);
        Kept   = Status == CCMAP_OK;
    }
    if (!Kept && (Status == CCMAP_OK || NeedsReinit != 0u || Status == CCMAP_NOT_INITIALISED ||
                  Status == CCMAP_CORRUPT))
    {
        Status             = ccmap_init(CCMAP_APP_Data.Map, &Params);
        Hk->MapInitialised = (Status == CCMAP_OK) ? 1u : 0u; /* a refused init leaves it uninitialised */
    }
    if (Status != CCMAP_OK)
    {
        Hk->LastStatus = Status; /* a refused set_params leaves the map as it was */
        CFE_EVS_SendEvent(CCMAP_APP_TBL_ERR_EID, CFE_EVS_EventType_ERROR,
                          "CCMAP: validated parameter table refused by the map: %s", ccmap_status_string(Status));
        return;
    }
    CCMAP_APP_Data.Table = *Tbl;
    Hk->CycleBudgetUs    = Tbl->CycleBudgetUs;
    ++Hk->TableUpdates;
    CFE_EVS_SendEvent(CCMAP_APP_TBL_INF_EID, CFE_EVS_EventType_INFORMATION,
                      "CCMAP: parameter table applied (%s), coverage_tau %.3f", Kept ? "map kept" : "map initialised",
                      (double)Tbl->CoverageTau);
}

void CCMAP_APP_ManageTable(void)
{
    void        *TblAddr = NULL;
    CFE_Status_t Status;

    (void)CFE_TBL_Manage(CCMAP_APP_Data.TblHandle);
    Status = CFE_TBL_GetAddress(&TblAddr, CCMAP_APP_Data.TblHandle);
    if (Status == CFE_TBL_INFO_UPDATED)
    {
        CCMAP_APP_ApplyTable((const CCMAP_APP_ParamTable_t *)TblAddr);
    }
    else if (Status != CFE_SUCCESS)
    {
        CFE_EVS_SendEvent(CCMAP_APP_TBL_ERR_EID, CFE_EVS_EventType_ERROR, "CCMAP: table address: 0x%08lX",
                          (unsigned long)Status);
    }
    if (Status == CFE_SUCCESS || Status == CFE_TBL_INFO_UPDATED)
    {
        (void)CFE_TBL_ReleaseAddress(CCMAP_APP_Data.TblHandle);
    }
}

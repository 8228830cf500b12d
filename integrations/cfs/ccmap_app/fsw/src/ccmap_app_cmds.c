/* ccmap_app command handlers. */
#include <string.h>

#include "ccmap_app.h"
#include "ccmap_app_cmds.h"
#include "ccmap_app_eventids.h"

/* One snapshot (SAVE/LOAD) and one product read back (PUBLISH): static. */
static uint8 CCMAP_APP_Snapshot[CCMAP_CADRE_SNAPSHOT_SIZE];
static uint8 CCMAP_APP_ProductCopy[CCMAP_PRODUCT_SIZE(CCMAP_APP_PRODUCT_CELLS, 1u)];

/* CRC-32 (IEEE 802.3, reflected, as the product's own). */
static uint32 CCMAP_APP_Crc32(const uint8 *Data, size_t Size)
{
    uint32 Crc = 0xFFFFFFFFu;
    size_t i;
    int    Bit;
    for (i = 0; i < Size; ++i)
    {
        Crc ^= Data[i];
        for (Bit = 0; Bit < 8; ++Bit)
        {
            Crc = (Crc >> 1) ^ (0xEDB88320u & (0u - (Crc & 1u)));
        }
    }
    return ~Crc;
}

static void CCMAP_APP_Refused(uint16 EventId, const char *What, ccmap_status Status)
{
    ++CCMAP_APP_Data.HkTlm.Payload.CommandErrorCounter;
    CCMAP_APP_Data.HkTlm.Payload.LastStatus = Status;
    CFE_EVS_SendEvent(EventId, CFE_EVS_EventType_ERROR, "CCMAP: %s refused: %s", What, ccmap_status_string(Status));
}

/* The command's file name, NUL-terminated whatever the ground sent. */
static void CCMAP_APP_FileName(const CCMAP_APP_FileCmd_t *Msg, char *Name, size_t Size)
{
    strncpy(Name, Msg->Payload.Filename, Size - 1u);
    Name[Size - 1u] = '\0';
}

void CCMAP_APP_NoopCmd(const CCMAP_APP_NoopCmd_t *Msg)
{
    (void)Msg;
    ++CCMAP_APP_Data.HkTlm.Payload.CommandCounter;
    CFE_EVS_SendEvent(CCMAP_APP_NOOP_INF_EID, CFE_EVS_EventType_INFORMATION, "CCMAP: NOOP, version %s",
                      CCMAP_APP_VERSION);
}

void CCMAP_APP_ResetCountersCmd(const CCMAP_APP_ResetCountersCmd_t *Msg)
{
    CCMAP_APP_HkTlm_Payload_t *Hk = &CCMAP_APP_Data.HkTlm.Payload;
    ccmap_status               Status;
    (void)Msg;
    Hk->CommandCounter      = 0;
    Hk->CommandErrorCounter = 0;
    Hk->FramesDropped       = 0;
    Hk->MaxFrameUs          = 0;
    Hk->BudgetOverruns      = 0;
    Hk->TableRefusals       = 0;
    Hk->FileErrors          = 0;
    Hk->LastStatus          = 0;
    Status                  = ccmap_reset_counters(CCMAP_APP_Data.Map);
    if (Status != CCMAP_OK)
    {
        CCMAP_APP_Refused(CCMAP_APP_CLEAR_ERR_EID, "reset of the map's counters", Status);
        return;
    }
    CFE_EVS_SendEvent(CCMAP_APP_RESET_INF_EID, CFE_EVS_EventType_INFORMATION, "CCMAP: counters reset");
}

void CCMAP_APP_ClearCmd(const CCMAP_APP_ClearCmd_t *Msg)
{
    ccmap_params Params;
    ccmap_status Status = CCMAP_APP_ParamsFromTable(&CCMAP_APP_Data.Table, &Params);
    (void)Msg;
    if (Status == CCMAP_OK)
    {
        Status = ccmap_init(CCMAP_APP_Data.Map, &Params);
        CCMAP_APP_Data.HkTlm.Payload.MapInitialised = (Status == CCMAP_OK) ? 1u : 0u;
    }
    if (Status != CCMAP_OK)
    {
        CCMAP_APP_Refused(CCMAP_APP_CLEAR_ERR_EID, "CLEAR", Status);
        return;
    }
    ++CCMAP_APP_Data.HkTlm.Payload.CommandCounter;
    CFE_EVS_SendEvent(CCMAP_APP_CLEAR_INF_EID, CFE_EVS_EventType_INFORMATION, "CCMAP: map cleared");
}

static void CCMAP_APP_FileFailed(const char *What, const char *Name, long Code)
{
    ++CCMAP_APP_Data.HkTlm.Payload.CommandErrorCounter;
    ++CCMAP_APP_Data.HkTlm.Payload.FileErrors;
    CFE_EVS_SendEvent(CCMAP_APP_FILE_ERR_EID, CFE_EVS_EventType_ERROR, "CCMAP: %s %s failed (%ld)", What, Name, Code);
}

void CCMAP_APP_SaveCmd(const CCMAP_APP_FileCmd_t *Msg)
{
    char         Name[CFE_MISSION_MAX_PATH_LEN];
    size_t       Written = 0;
    size_t       Done    = 0;
    osal_id_t    Fd      = OS_OBJECT_ID_UNDEFINED;
    int32        Rc;
    ccmap_status Status;

    CCMAP_APP_FileName(Msg, Name, sizeof(Name));
    Status = ccmap_save_snapshot(CCMAP_APP_Data.Map, CCMAP_APP_Snapshot, sizeof(CCMAP_APP_Snapshot), &Written);
    if (Status != CCMAP_OK)
    {
        ++CCMAP_APP_Data.HkTlm.Payload.FileErrors;
        CCMAP_APP_Refused(CCMAP_APP_SNAPSHOT_ERR_EID, "SAVE", Status);
        return;
    }
    Rc = OS_OpenCreate(&Fd, Name, OS_FILE_FLAG_CREATE | OS_FILE_FLAG_TRUNCATE, OS_WRITE_ONLY);
    if (Rc != OS_SUCCESS)
    {
        CCMAP_APP_FileFailed("SAVE: open", Name, Rc);
        return;
    }
    while (Done < Written)
    {
        Rc = OS_write(Fd, CCMAP_APP_Snapshot + Done, Written - Done);
        if (Rc <= 0)
        {
            break;
        }
        Done += (size_t)Rc;
    }
    OS_close(Fd);
    if (Done != Written)
    {
        CCMAP_APP_FileFailed("SAVE: write", Name, Rc);
        return;
    }
    ++CCMAP_APP_Data.HkTlm.Payload.CommandCounter;
    CFE_EVS_SendEvent(CCMAP_APP_SAVE_INF_EID, CFE_EVS_EventType_INFORMATION, "CCMAP: map saved to %s (%lu bytes)",
                      Name, (unsigned long)Written);
}

void CCMAP_APP_LoadCmd(const CCMAP_APP_FileCmd_t *Msg)
{
    char         Name[CFE_MISSION_MAX_PATH_LEN];
    uint8        Extra = 0;
    size_t       Done  = 0;
    osal_id_t    Fd    = OS_OBJECT_ID_UNDEFINED;
    int32        Rc    = 0;
    ccmap_status Status;

    CCMAP_APP_FileName(Msg, Name, sizeof(Name));
    Rc = OS_OpenCreate(&Fd, Name, OS_FILE_FLAG_NONE, OS_READ_ONLY);
    if (Rc != OS_SUCCESS)
    {
        CCMAP_APP_FileFailed("LOAD: open", Name, Rc);
        return;
    }
    while (Done < sizeof(CCMAP_APP_Snapshot))
    {
        Rc = OS_read(Fd, CCMAP_APP_Snapshot + Done, sizeof(CCMAP_APP_Snapshot) - Done);
        if (Rc <= 0)
        {
            break;
        }
        Done += (size_t)Rc;
    }
    if (Rc >= 0 && Done == sizeof(CCMAP_APP_Snapshot) && OS_read(Fd, &Extra, 1) > 0)
    {
        Rc = -1; /* longer than any snapshot of this preset */
    }
    OS_close(Fd);
    if (Rc < 0)
    {
        CCMAP_APP_FileFailed("LOAD: read", Name, Rc);
        return;
    }
    /* All or nothing: on a refusal the map is bitwise unchanged. */
    Status = ccmap_load_snapshot(CCMAP_APP_Data.Map, CCMAP_APP_Snapshot, Done);
    if (Status != CCMAP_OK)
    {
        ++CCMAP_APP_Data.HkTlm.Payload.FileErrors;
        CCMAP_APP_Refused(CCMAP_APP_SNAPSHOT_ERR_EID, "LOAD", Status);
        return;
    }
    CCMAP_APP_Data.HkTlm.Payload.MapInitialised = 1;
    ++CCMAP_APP_Data.HkTlm.Payload.CommandCounter;
    CFE_EVS_SendEvent(CCMAP_APP_LOAD_INF_EID, CFE_EVS_EventType_INFORMATION, "CCMAP: map loaded from %s (%lu bytes)",
                      Name, (unsigned long)Done);
}

void CCMAP_APP_LoadTableCmd(const CCMAP_APP_FileCmd_t *Msg)
{
    char         Name[CFE_MISSION_MAX_PATH_LEN];
    uint32       Updates = CCMAP_APP_Data.HkTlm.Payload.TableUpdates;
    CFE_Status_t Status;

    CCMAP_APP_FileName(Msg, Name, sizeof(Name));
    /* Table services read the file and call CCMAP_APP_ValidateTable; a refused image never
     * becomes active. The owner's load is what works in cFE 7.0.0, whose ground LOAD command
     * fails for every table ("No working buffers available": nasa/cFS issue 892). */
    Status = CFE_TBL_Load(CCMAP_APP_Data.TblHandle, CFE_TBL_SRC_FILE, Name);
    if (Status == CFE_SUCCESS)
    {
        CCMAP_APP_ManageTable();
    }
    if (Status != CFE_SUCCESS || CCMAP_APP_Data.HkTlm.Payload.TableUpdates == Updates)
    {
        ++CCMAP_APP_Data.HkTlm.Payload.CommandErrorCounter;
        CFE_EVS_SendEvent(CCMAP_APP_TBL_ERR_EID, CFE_EVS_EventType_ERROR,
                          "CCMAP: parameter table %s not loaded (0x%08lX): the active table is kept", Name,
                          (unsigned long)Status);
        return;
    }
    ++CCMAP_APP_Data.HkTlm.Payload.CommandCounter;
}

void CCMAP_APP_PublishCmd(const CCMAP_APP_PublishCmd_t *Msg)
{
    CCMAP_APP_HkTlm_Payload_t      *Hk   = &CCMAP_APP_Data.HkTlm.Payload;
    CCMAP_APP_ProductTlm_Payload_t *Tlm  = &CCMAP_APP_Data.ProductTlm.Payload;
    ccmap_product_spec              Spec = {0};
    ccmap_product_header            Header;
    size_t                          Written = 0;
    ccmap_status                    Status;
    (void)Msg;

    Spec.layer  = CCMAP_APP_PRODUCT_LAYER;
    Spec.answer = CCMAP_PRODUCT_STACK;
    Spec.pose_x = CCMAP_APP_Data.LastPose[0];
    Spec.pose_y = CCMAP_APP_Data.LastPose[1];
    Spec.pose_z = CCMAP_APP_Data.LastPose[2];
    Spec.tag    = Hk->ProductSequence + 1u;
    Status      = ccmap_publish(CCMAP_APP_Data.Map, &Spec, &CCMAP_APP_Data.Products);
    /* Read back as a reader in another task would: the whole product, checked. */
    if (Status == CCMAP_OK)
    {
        Status = ccmap_product_read(&CCMAP_APP_Data.Products, CCMAP_APP_ProductCopy, sizeof(CCMAP_APP_ProductCopy),
                                    &Written);
    }
    if (Status == CCMAP_OK)
    {
        Status = ccmap_product_decode(CCMAP_APP_ProductCopy, Written, &Header, NULL, 0);
    }
    Tlm->Status = Status;
    if (Status != CCMAP_OK)
    {
        CCMAP_APP_Refused(CCMAP_APP_PUBLISH_ERR_EID, "PUBLISH", Status);
        return;
    }
    Hk->ProductSequence = Header.product_sequence;
    Hk->ProductBytes    = (uint32)Written;
    Hk->ProductCrc      = (uint32)CCMAP_APP_ProductCopy[Written - 4u] |
                     ((uint32)CCMAP_APP_ProductCopy[Written - 3u] << 8) |
                     ((uint32)CCMAP_APP_ProductCopy[Written - 2u] << 16) |
                     ((uint32)CCMAP_APP_ProductCopy[Written - 1u] << 24);
    Hk->ProductCellsCrc = CCMAP_APP_Crc32(CCMAP_APP_ProductCopy + CCMAP_PRODUCT_HEADER_SIZE,
                                          Written - CCMAP_PRODUCT_HEADER_SIZE - CCMAP_PRODUCT_CRC_SIZE);
    Tlm->Sequence       = Hk->ProductSequence;
    Tlm->Crc            = Hk->ProductCrc;
    Tlm->CellsCrc       = Hk->ProductCellsCrc;
    Tlm->Bytes          = Hk->ProductBytes;
    ++Hk->CommandCounter;
    CFE_SB_TimeStampMsg(CFE_MSG_PTR(CCMAP_APP_Data.ProductTlm.TelemetryHeader));
    CFE_SB_TransmitMsg(CFE_MSG_PTR(CCMAP_APP_Data.ProductTlm.TelemetryHeader), true);
    CFE_EVS_SendEvent(CCMAP_APP_PUBLISH_INF_EID, CFE_EVS_EventType_INFORMATION,
                      "CCMAP: product %lu published, %lu bytes, CRC 0x%08lX, cells CRC 0x%08lX",
                      (unsigned long)Hk->ProductSequence, (unsigned long)Written, (unsigned long)Hk->ProductCrc,
                      (unsigned long)Hk->ProductCellsCrc);
}

void CCMAP_APP_SendHkCmd(const CCMAP_APP_SendHkCmd_t *Msg)
{
    CCMAP_APP_HkTlm_Payload_t *Hk = &CCMAP_APP_Data.HkTlm.Payload;
    ccmap_health               Health;
    ccmap_params               Params;
    int32                      Layer;
    (void)Msg;

    CCMAP_APP_ManageTable();
    if (ccmap_get_health(CCMAP_APP_Data.Map, &Health) == CCMAP_OK)
    {
        if (Health.state == CCMAP_CORRUPT && Hk->HealthState != CCMAP_CORRUPT)
        {
            CFE_EVS_SendEvent(CCMAP_APP_HEALTH_ERR_EID, CFE_EVS_EventType_CRITICAL,
                              "CCMAP: the map failed its state check: CLEAR or LOAD a snapshot");
        }
        Hk->HealthState         = Health.state;
        Hk->FramesAccepted      = Health.frames_accepted;
        Hk->FramesRefused       = Health.frames_refused;
        Hk->PointsReceived      = Health.points_received;
        Hk->PointsUsed          = Health.points_used;
        Hk->PointsSkippedBudget = Health.points_skipped_budget;
        Hk->CorruptedCells      = Health.corrupted_cells;
        Hk->ParamsCrc           = Health.params_crc;
        Hk->MapSequence         = Health.map_sequence;
        Hk->LibraryFaults       = Health.fault_count;
        Hk->ObservedCells       = 0;
        for (Layer = 0; Layer < Health.layer_count && Layer < CCMAP_MAX_LAYERS; ++Layer)
        {
            Hk->ObservedCells += Health.layers[Layer].observed_cells;
        }
    }
    if (ccmap_get_params(CCMAP_APP_Data.Map, &Params) == CCMAP_OK)
    {
        Hk->CoverageTau      = Params.coverage_tau;
        Hk->OutlierGateSigma = Params.outlier_gate_sigma;
        Hk->FramePointBudget = Params.frame_point_budget;
    }
    CFE_SB_TimeStampMsg(CFE_MSG_PTR(CCMAP_APP_Data.HkTlm.TelemetryHeader));
    CFE_SB_TransmitMsg(CFE_MSG_PTR(CCMAP_APP_Data.HkTlm.TelemetryHeader), true);
}

/* ccmap_app command and telemetry packets. Payloads hold 4-byte fields only (natural alignment,
 * no padding), in the cpu's byte order after the big-endian CCSDS header: a command is the 8-byte
 * command header plus its payload, a telemetry packet the 16-byte telemetry header plus its
 * payload. integrations/cfs/ground/ccmap_ground.py encodes and decodes them. */
#ifndef CCMAP_APP_MSG_H
#define CCMAP_APP_MSG_H

#include "cfe_msg_hdr.h"
#include "cfe_mission_cfg.h"

/* ---- commands (CCMAP_APP_CMD_MID; function codes in ccmap_app_fcncodes.h) ---- */
typedef struct
{
    CFE_MSG_CommandHeader_t CommandHeader;
} CCMAP_APP_NoArgsCmd_t; /* NOOP, RESET_COUNTERS, CLEAR, PUBLISH */

typedef CCMAP_APP_NoArgsCmd_t CCMAP_APP_NoopCmd_t;
typedef CCMAP_APP_NoArgsCmd_t CCMAP_APP_ResetCountersCmd_t;
typedef CCMAP_APP_NoArgsCmd_t CCMAP_APP_ClearCmd_t;
typedef CCMAP_APP_NoArgsCmd_t CCMAP_APP_PublishCmd_t;
typedef CCMAP_APP_NoArgsCmd_t CCMAP_APP_SendHkCmd_t; /* CCMAP_APP_SEND_HK_MID, from the scheduler */

typedef struct
{
    char Filename[CFE_MISSION_MAX_PATH_LEN]; /* OSAL virtual path, NUL-terminated, e.g. "/cf/map.snap" */
} CCMAP_APP_File_Payload_t;

typedef struct
{
    CFE_MSG_CommandHeader_t  CommandHeader;
    CCMAP_APP_File_Payload_t Payload;
} CCMAP_APP_FileCmd_t; /* SAVE, LOAD, LOAD_TABLE */

/* ---- housekeeping (CCMAP_APP_HK_TLM_MID, on every CCMAP_APP_SEND_HK_MID) ---- */
typedef struct
{
    uint32 CommandCounter;      /* commands accepted */
    uint32 CommandErrorCounter; /* commands and messages refused: length, code, message ID, file,
                                   library (each with an event) */
    uint32 FramesAccepted;      /* the library's counters since init, load or RESET_COUNTERS */
    uint32 FramesRefused;       /*   frames it refused as a whole (LastStatus says why) */
    uint32 FramesDropped;       /* FRAME_READY messages refused before the library: bad length,
                                   slot or sequence, slot not ready (the app's) */
    uint32 PointsReceived;      /* the library's, over the accepted frames (saturating) */
    uint32 PointsUsed;
    uint32 PointsSkippedBudget; /* left out by the library's frame point/time budget */
    uint32 LastFrameUs;         /* the last frame's handling, us: from the message to the slot's release */
    uint32 LastLibraryUs;       /*   of which the library call */
    uint32 MaxFrameUs;          /* the longest handling since RESET_COUNTERS */
    uint32 BudgetOverruns;      /* frames whose handling took more than CycleBudgetUs */
    uint32 CycleBudgetUs;       /* the active table's budget for one frame */
    uint32 TableUpdates;        /* parameter tables applied */
    uint32 TableRefusals;       /* parameter tables the library's validation refused (the old one kept) */
    uint32 FileErrors;          /* SAVE/LOAD refused: file or library */
    uint32 ProductSequence;     /* the last product's sequence (ccmap_product_header) */
    uint32 ProductCrc;          /* its own CRC-32 (the product's last 4 bytes) */
    uint32 ProductCellsCrc;     /* CRC-32 of its cells only: equal for equal maps, whatever the sequence */
    uint32 ProductBytes;
    int32  LastStatus;          /* ccmap_status of the last refused library call (0: none) */
    int32  HealthState;         /* ccmap_health.state, checked at this HK: 0 ok, 8 not initialised, 9 corrupt */
    uint32 MapInitialised;      /* 1 when the map is initialised */
    uint32 ObservedCells;       /* cells holding points, all layers */
    uint32 CorruptedCells;      /* upsets the library's scrub found and reset */
    uint32 ParamsCrc;           /* ccmap_health.params_crc: identity of the parameters in use */
    uint32 MapSequence;         /* frame updates since init or load */
    uint32 LibraryFaults;       /* contract violations the library reported (each also an event) */
    float  CoverageTau;         /* the parameters in use (ccmap_get_params) */
    float  OutlierGateSigma;
    uint32 FramePointBudget;
} CCMAP_APP_HkTlm_Payload_t;

typedef struct
{
    CFE_MSG_TelemetryHeader_t TelemetryHeader;
    CCMAP_APP_HkTlm_Payload_t Payload;
} CCMAP_APP_HkTlm_t;

/* ---- product summary (CCMAP_APP_PRODUCT_TLM_MID, on every PUBLISH) ---- */
typedef struct
{
    uint32 Sequence; /* equals HK ProductSequence */
    uint32 Crc;      /* the product's own CRC-32 (its last 4 bytes) */
    uint32 CellsCrc; /* CRC-32 of its cells only */
    uint32 Bytes;
    int32  Status;   /* ccmap_status of the publish */
} CCMAP_APP_ProductTlm_Payload_t;

typedef struct
{
    CFE_MSG_TelemetryHeader_t      TelemetryHeader;
    CCMAP_APP_ProductTlm_Payload_t Payload;
} CCMAP_APP_ProductTlm_t;

#endif

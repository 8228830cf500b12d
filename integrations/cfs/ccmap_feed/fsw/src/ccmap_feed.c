/* ccmap_feed: the test's frame producer (see CMakeLists.txt). Commands on CCMAP_FEED_CMD_MID:
 * code 0 NOOP, code 1 FEED with a 64-byte OSAL path. A frame file is a 64-byte header in the
 * cpu's byte order (magic "CCF1", uint32 point count, float rotation[9] and translation[3] of the
 * sensor pose, 8 spare bytes) and then the sensor-frame points, 3 floats each. */
#include <string.h>

#include "cfe.h"
#include "ccmap_frames.h"

#define CCMAP_FEED_CMD_MID  CFE_PLATFORM_CMD_TOPICID_TO_MIDV(0xA4)
#define CCMAP_FEED_NOOP_CC  0
#define CCMAP_FEED_FEED_CC  1
#define CCMAP_FEED_INIT_EID 1
#define CCMAP_FEED_NOOP_EID 2
#define CCMAP_FEED_FED_EID  3
#define CCMAP_FEED_ERR_EID  4 /* any refusal: bad command, no free slot, bad file */

typedef struct
{
    CFE_MSG_CommandHeader_t CommandHeader;
    char                    Filename[CFE_MISSION_MAX_PATH_LEN];
} CCMAP_FEED_FeedCmd_t;

typedef struct
{
    char   Magic[4];
    uint32 NumPoints;
    float  Rotation[9];
    float  Translation[3];
    uint32 Spare[2];
} CCMAP_FEED_FileHeader_t;

static CFE_SB_PipeId_t         CCMAP_FEED_Pipe;
static CCMAP_FRAMES_ReadyMsg_t CCMAP_FEED_ReadyMsg;

/* Reads exactly Size bytes; false on a short read or an error. */
static bool CCMAP_FEED_ReadAll(osal_id_t Fd, void *Dest, size_t Size)
{
    uint8 *Ptr = Dest;
    while (Size > 0)
    {
        int32 Got = OS_read(Fd, Ptr, Size);
        if (Got <= 0)
        {
            return false;
        }
        Ptr += Got;
        Size -= (size_t)Got;
    }
    return true;
}

static void CCMAP_FEED_Feed(const CCMAP_FEED_FeedCmd_t *Cmd)
{
    char                    Name[CFE_MISSION_MAX_PATH_LEN];
    CCMAP_FEED_FileHeader_t Header;
    CCMAP_FRAMES_Slot_t    *SlotPtr;
    uint32                  Slot     = 0;
    uint32                  Sequence = 0;
    osal_id_t               Fd       = OS_OBJECT_ID_UNDEFINED;
    bool                    Ok;

    strncpy(Name, Cmd->Filename, sizeof(Name) - 1);
    Name[sizeof(Name) - 1] = '\0';
    SlotPtr                = CCMAP_FRAMES_Acquire(&Slot);
    if (SlotPtr == NULL)
    {
        CFE_EVS_SendEvent(CCMAP_FEED_ERR_EID, CFE_EVS_EventType_ERROR, "FEED: no free frame slot");
        return;
    }
    Ok = OS_OpenCreate(&Fd, Name, OS_FILE_FLAG_NONE, OS_READ_ONLY) == OS_SUCCESS;
    Ok = Ok && CCMAP_FEED_ReadAll(Fd, &Header, sizeof(Header)) && memcmp(Header.Magic, "CCF1", 4) == 0 &&
         Header.NumPoints <= CCMAP_FRAMES_MAX_POINTS &&
         CCMAP_FEED_ReadAll(Fd, SlotPtr->Xyz, (size_t)Header.NumPoints * 3u * sizeof(float));
    if (OS_ObjectIdDefined(Fd))
    {
        OS_close(Fd);
    }
    if (Ok)
    {
        SlotPtr->NumPoints = Header.NumPoints;
        memcpy(SlotPtr->Rotation, Header.Rotation, sizeof(Header.Rotation));
        memcpy(SlotPtr->Translation, Header.Translation, sizeof(Header.Translation));
        Ok = CCMAP_FRAMES_Ready(Slot, &Sequence) == CFE_SUCCESS;
    }
    if (!Ok)
    {
        CCMAP_FRAMES_Release(Slot);
        CFE_EVS_SendEvent(CCMAP_FEED_ERR_EID, CFE_EVS_EventType_ERROR, "FEED: cannot read frame file %s", Name);
        return;
    }
    CCMAP_FEED_ReadyMsg.Payload.Slot     = Slot;
    CCMAP_FEED_ReadyMsg.Payload.Sequence = Sequence;
    CFE_SB_TransmitMsg(CFE_MSG_PTR(CCMAP_FEED_ReadyMsg.CommandHeader), true);
    CFE_EVS_SendEvent(CCMAP_FEED_FED_EID, CFE_EVS_EventType_INFORMATION, "FEED: %s -> slot %u seq %u (%u points)", Name,
                      (unsigned)Slot, (unsigned)Sequence, (unsigned)Header.NumPoints);
}

static void CCMAP_FEED_Process(const CFE_SB_Buffer_t *Buf)
{
    CFE_MSG_FcnCode_t Code = 0;
    size_t            Size = 0;
    CFE_MSG_GetFcnCode(&Buf->Msg, &Code);
    CFE_MSG_GetSize(&Buf->Msg, &Size);
    if (Code == CCMAP_FEED_NOOP_CC && Size == sizeof(CFE_MSG_CommandHeader_t))
    {
        CFE_EVS_SendEvent(CCMAP_FEED_NOOP_EID, CFE_EVS_EventType_INFORMATION, "FEED: NOOP");
    }
    else if (Code == CCMAP_FEED_FEED_CC && Size == sizeof(CCMAP_FEED_FeedCmd_t))
    {
        CCMAP_FEED_Feed((const CCMAP_FEED_FeedCmd_t *)Buf);
    }
    else
    {
        CFE_EVS_SendEvent(CCMAP_FEED_ERR_EID, CFE_EVS_EventType_ERROR, "FEED: bad command code %u length %u",
                          (unsigned)Code, (unsigned)Size);
    }
}

void CCMAP_FEED_Main(void)
{
    uint32           RunStatus = CFE_ES_RunStatus_APP_RUN;
    CFE_SB_Buffer_t *Buf;

    if (CFE_EVS_Register(NULL, 0, CFE_EVS_EventFilter_BINARY) != CFE_SUCCESS ||
        CFE_SB_CreatePipe(&CCMAP_FEED_Pipe, 4, "CCMAP_FEED_PIPE") != CFE_SUCCESS ||
        CFE_SB_Subscribe(CFE_SB_ValueToMsgId(CCMAP_FEED_CMD_MID), CCMAP_FEED_Pipe) != CFE_SUCCESS)
    {
        RunStatus = CFE_ES_RunStatus_APP_ERROR;
    }
    CFE_MSG_Init(CFE_MSG_PTR(CCMAP_FEED_ReadyMsg.CommandHeader), CFE_SB_ValueToMsgId(CCMAP_FRAMES_READY_MID),
                 sizeof(CCMAP_FEED_ReadyMsg));
    CFE_EVS_SendEvent(CCMAP_FEED_INIT_EID, CFE_EVS_EventType_INFORMATION, "FEED: initialized");
    while (CFE_ES_RunLoop(&RunStatus))
    {
        if (CFE_SB_ReceiveBuffer(&Buf, CCMAP_FEED_Pipe, CFE_SB_PEND_FOREVER) == CFE_SUCCESS)
        {
            CCMAP_FEED_Process(Buf);
        }
        else
        {
            RunStatus = CFE_ES_RunStatus_APP_ERROR;
        }
    }
    CFE_ES_ExitApp(RunStatus);
}

/* ccmap_app message dispatch. */
#include "ccmap_app.h"
#include "ccmap_app_cmds.h"
#include "ccmap_app_dispatch.h"
#include "ccmap_app_eventids.h"

bool CCMAP_APP_VerifyLength(const CFE_MSG_Message_t *MsgPtr, size_t ExpectedLength)
{
    size_t            ActualLength = 0;
    CFE_SB_MsgId_t    MsgId        = CFE_SB_INVALID_MSG_ID;
    CFE_MSG_FcnCode_t FcnCode      = 0;

    CFE_MSG_GetSize(MsgPtr, &ActualLength);
    if (ActualLength == ExpectedLength)
    {
        return true;
    }
    CFE_MSG_GetMsgId(MsgPtr, &MsgId);
    CFE_MSG_GetFcnCode(MsgPtr, &FcnCode);
    CFE_EVS_SendEvent(CCMAP_APP_LEN_ERR_EID, CFE_EVS_EventType_ERROR,
                      "CCMAP: invalid length: MID 0x%X, CC %u, length %u, expected %u",
                      (unsigned)CFE_SB_MsgIdToValue(MsgId), (unsigned)FcnCode, (unsigned)ActualLength,
                      (unsigned)ExpectedLength);
    ++CCMAP_APP_Data.HkTlm.Payload.CommandErrorCounter;
    return false;
}

static void CCMAP_APP_ProcessGroundCommand(const CFE_SB_Buffer_t *SBBufPtr)
{
    CFE_MSG_FcnCode_t CommandCode = 0;

    CFE_MSG_GetFcnCode(&SBBufPtr->Msg, &CommandCode);
    switch (CommandCode)
    {
        case CCMAP_APP_NOOP_CC:
            if (CCMAP_APP_VerifyLength(&SBBufPtr->Msg, sizeof(CCMAP_APP_NoopCmd_t)))
            {
                CCMAP_APP_NoopCmd((const CCMAP_APP_NoopCmd_t *)SBBufPtr);
            }
            break;
        case CCMAP_APP_RESET_COUNTERS_CC:
            if (CCMAP_APP_VerifyLength(&SBBufPtr->Msg, sizeof(CCMAP_APP_ResetCountersCmd_t)))
            {
                CCMAP_APP_ResetCountersCmd((const CCMAP_APP_ResetCountersCmd_t *)SBBufPtr);
            }
            break;
        case CCMAP_APP_CLEAR_CC:
            if (CCMAP_APP_VerifyLength(&SBBufPtr->Msg, sizeof(CCMAP_APP_ClearCmd_t)))
            {
                CCMAP_APP_ClearCmd((const CCMAP_APP_ClearCmd_t *)SBBufPtr);
            }
            break;
        case CCMAP_APP_SAVE_CC:
            if (CCMAP_APP_VerifyLength(&SBBufPtr->Msg, sizeof(CCMAP_APP_FileCmd_t)))
            {
                CCMAP_APP_SaveCmd((const CCMAP_APP_FileCmd_t *)SBBufPtr);
            }
            break;
        case CCMAP_APP_LOAD_CC:
            if (CCMAP_APP_VerifyLength(&SBBufPtr->Msg, sizeof(CCMAP_APP_FileCmd_t)))
            {
                CCMAP_APP_LoadCmd((const CCMAP_APP_FileCmd_t *)SBBufPtr);
            }
            break;
        case CCMAP_APP_LOAD_TABLE_CC:
            if (CCMAP_APP_VerifyLength(&SBBufPtr->Msg, sizeof(CCMAP_APP_FileCmd_t)))
            {
                CCMAP_APP_LoadTableCmd((const CCMAP_APP_FileCmd_t *)SBBufPtr);
            }
            break;
        case CCMAP_APP_PUBLISH_CC:
            if (CCMAP_APP_VerifyLength(&SBBufPtr->Msg, sizeof(CCMAP_APP_PublishCmd_t)))
            {
                CCMAP_APP_PublishCmd((const CCMAP_APP_PublishCmd_t *)SBBufPtr);
            }
            break;
        default:
            ++CCMAP_APP_Data.HkTlm.Payload.CommandErrorCounter;
            CFE_EVS_SendEvent(CCMAP_APP_CC_ERR_EID, CFE_EVS_EventType_ERROR, "CCMAP: invalid command code %u",
                              (unsigned)CommandCode);
            break;
    }
}

void CCMAP_APP_TaskPipe(const CFE_SB_Buffer_t *SBBufPtr)
{
    CFE_SB_MsgId_t MsgId = CFE_SB_INVALID_MSG_ID;

    CFE_MSG_GetMsgId(&SBBufPtr->Msg, &MsgId);
    switch (CFE_SB_MsgIdToValue(MsgId))
    {
        case CCMAP_FRAMES_READY_MID:
            CCMAP_APP_FrameReady(SBBufPtr);
            break;
        case CCMAP_APP_CMD_MID:
            CCMAP_APP_ProcessGroundCommand(SBBufPtr);
            break;
        case CCMAP_APP_SEND_HK_MID:
            if (CCMAP_APP_VerifyLength(&SBBufPtr->Msg, sizeof(CCMAP_APP_SendHkCmd_t)))
            {
                CCMAP_APP_SendHkCmd((const CCMAP_APP_SendHkCmd_t *)SBBufPtr);
            }
            break;
        default:
            ++CCMAP_APP_Data.HkTlm.Payload.CommandErrorCounter;
            CFE_EVS_SendEvent(CCMAP_APP_MID_ERR_EID, CFE_EVS_EventType_ERROR, "CCMAP: invalid message ID 0x%X",
                              (unsigned)CFE_SB_MsgIdToValue(MsgId));
            break;
    }
}

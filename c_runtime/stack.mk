# Static stack bound of the flight code (included by the top Makefile; guidance/stack_bound.py).
#   make stack-info -> every flight source compiled again exactly as the flight build compiles
#                      it (the same flags: inlining decides the frames) with GCC's
#                      -fstack-usage and -fcallgraph-info=su, into $(STACK_DIR): per unit a
#                      .su (frame sizes and qualifiers) and a .ci (call graph with the frames),
#                      and $(STACK_DIR)/units, the list of .ci files. The objects are thrown
#                      away; the library is built from $(BUILD)/obj as always.

STACK_DIR   := $(BUILD)/stack
STACK_FLAGS := -fstack-usage -fcallgraph-info=su
STACK_CI    := $(patsubst $(CRT_DIR)/src/%.c,$(STACK_DIR)/crt/%.ci,$(CRT_SRCS)) \
               $(patsubst c_runtime/nn/%.c,$(STACK_DIR)/nn/%.ci,$(NN_SRCS)) \
               $(patsubst c_runtime/guidance/%.c,$(STACK_DIR)/gnc/%.ci,$(GNC_SRCS)) \
               $(STACK_DIR)/gnc/tscvx_model.ci

# GCC writes x.su and x.ci beside the object x.o; each rule's flags are its flight rule's.
$(STACK_DIR)/crt/%.ci: $(CRT_DIR)/src/%.c $(CRT_HDRS) $(FLAGS_STAMP)
	@mkdir -p $(@D)
	$(CRT_CC) $(CRT_CFLAGS) $(STACK_FLAGS) -c $< -o $(@:.ci=.o)
$(STACK_DIR)/nn/%.ci: c_runtime/nn/%.c $(NN_HDRS) $(FLAGS_STAMP)
	@mkdir -p $(@D)
	$(CC) $(NN_CFLAGS) $(STACK_FLAGS) -c $< -o $(@:.ci=.o)
$(STACK_DIR)/gnc/tscvx_model.ci: $(GEN_DIR)/tscvx_model.c $(FLAGS_STAMP)
	@mkdir -p $(@D)
	$(CC) $(GNC_CFLAGS) -Wno-unused-parameter -Wno-missing-prototypes $(STACK_FLAGS) -c $< -o $(@:.ci=.o)
$(STACK_DIR)/gnc/%.ci: c_runtime/guidance/%.c $(GNC_HDRS) $(GEN_DIR)/tscvx_model.h $(FLAGS_STAMP)
	@mkdir -p $(@D)
	$(CC) $(GNC_CFLAGS) $(STACK_FLAGS) -c $< -o $(@:.ci=.o)

# the list is rewritten only when it changes (a source added or removed)
$(STACK_DIR)/units: $(STACK_CI)
	@printf '%s\n' $(STACK_CI) | cmp -s - $@ || printf '%s\n' $(STACK_CI) > $@

stack-info: $(STACK_DIR)/units

.PHONY: stack-info

# Generated model and guidance layer of the flight library (included by the top Makefile).
#   $(BUILD)/generated/tscvx_model.[ch]  CasADi -> C (codegen/generate.py), reproducible
#   $(BUILD)/libtscvx_gnc.{a,so}           generated model + FOH discretization

GEN_DIR    := $(BUILD)/generated
GNC_OBJDIR := $(BUILD)/obj/gnc
GNC_SRCS   := $(wildcard c_runtime/guidance/*.c)
GNC_OBJS   := $(patsubst c_runtime/guidance/%.c,$(GNC_OBJDIR)/%.o,$(GNC_SRCS)) $(GNC_OBJDIR)/tscvx_model.o
GNC_CFLAGS := -std=c99 -Wall -Wextra -Werror -O2 -fPIC -Ic_runtime/include -Ic_runtime/guidance -I$(GEN_DIR)

$(GEN_DIR)/tscvx_model.c $(GEN_DIR)/tscvx_model.h &: codegen/generate.py guidance/model.py | $(STAMP)
	$(PY) codegen/generate.py $(GEN_DIR)

# CasADi's generated entry points share one signature and ignore some arguments.
$(GNC_OBJDIR)/tscvx_model.o: $(GEN_DIR)/tscvx_model.c
	@mkdir -p $(GNC_OBJDIR)
	$(CC) $(GNC_CFLAGS) -Wno-unused-parameter -c $< -o $@

$(GNC_OBJDIR)/%.o: c_runtime/guidance/%.c $(wildcard c_runtime/guidance/*.h) $(GEN_DIR)/tscvx_model.h
	@mkdir -p $(GNC_OBJDIR)
	$(CC) $(GNC_CFLAGS) -c $< -o $@

$(BUILD)/libtscvx_gnc.a: $(GNC_OBJS)
	rm -f $@
	ar rcs $@ $(GNC_OBJS)

$(BUILD)/libtscvx_gnc.so: $(GNC_OBJS)
	$(CC) -shared -o $@ $(GNC_OBJS) -lm

gnc: $(BUILD)/libtscvx_gnc.a $(BUILD)/libtscvx_gnc.so
lib: gnc

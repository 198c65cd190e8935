;;;; tools/mutate.lisp -- make mutate: how many plausible defects do the claims notice?
;;;;
;;;; Usage (from the repository): make mutate [SEED=n] [COUNT=n] [ANCHOR=ID] [JOBS=n]
;;;; The section "How the claims are tested" of physics.org explains the method.  In short:
;;;; this image loads the engine and the claims once, times every claim on the unchanged
;;;; engine, and then, for each sampled mutant (one operator applied at one place of one
;;;; definition of the tangled engine), forks a child that evaluates the mutated definition
;;;; and every form that inlines it or is generated from it, and runs the claims, cheapest
;;;; first, until one fails.  Two children run at a time.  Output: one line per mutant, then
;;;; the score per part; the tables go to report/mutate-score.org and
;;;; report/mutate-survivors.org, which make mutate splices into the page.

(load (merge-pathnames "boot.lisp" *load-truename*))
(require :sb-posix)

(in-package #:cl-user)

(when (luv-load-systems "luv-physics/tests")
  (sb-ext:exit :code 2))

(defpackage #:luv-mutate
  (:use #:cl)
  (:local-nicknames (#:5am #:fiveam) (#:physics #:luv-physics)))

(in-package #:luv-mutate)

;; The file is loaded as source, each toplevel form compiled on its own, so a call of a
;; function defined further down would be noted as undefined when its caller is compiled.
(declaim (ftype function featured-texts now proper-list-p renew-featured-variants replace-nth
                variable-symbol-p walk-call write-score-rows write-score-rows-by))

(defparameter *engine-files* '("tangled/physics.lisp" "tangled/physics-simd.lisp")
  "The tangled files whose definitions are mutated.")

(defparameter *dependent-files* '("tangled/physics.lisp" "tangled/physics-simd.lisp"
                                  "tangled/workshop.lisp" "tests/physics-tests.lisp")
  "The files whose forms may inline, or be generated from, a mutated definition.")

(defparameter *mutant-records* "tests/mutant-records.org"
  "The file of the mutant records: why a mutant that survives is equivalent, or survives.")

(defparameter *mutable-kinds* '(defun defmacro defmethod defparameter)
  "Standard defining operators whose forms are mutated; any operator of the page's own
whose name starts with DEF (a macro of the engine's package) is mutated too.")

;;; ------------------------------------------------------------------------------------
;;; Reading the tangled files: one record per toplevel form

(defstruct unit
  form          ; the form as read
  file line anchor package
  name          ; the first definition's name, for the report
  kind          ; its operator
  symbols       ; every symbol the form mentions (a hash set)
  defines       ; the names it defines
  mutable)      ; true if it is mutated

(defun comma-p (x) (typep x 'sb-impl::comma))

(defun map-tree-symbols (function tree)
  "Call FUNCTION on every symbol in TREE, looking inside backquote commas."
  (let ((seen (make-hash-table :test #'eq)))
    (labels ((walk (x)
               (cond ((symbolp x) (funcall function x))
                     ((comma-p x) (walk (sb-impl::comma-expr x)))
                     ((consp x)
                      (unless (gethash x seen)
                        (setf (gethash x seen) t)
                        (walk (car x)) (walk (cdr x)))))))
      (walk tree))))

(defun engine-defining-operator-p (operator)
  (and (symbolp operator)
       (or (member operator *mutable-kinds*)
           (and (eq (symbol-package operator) (find-package '#:luv-physics))
                (physics::defining-operator-p operator)
                (macro-function operator)))))

(defun defined-names (form)
  "The names FORM defines, looking through PROGN, EVAL-WHEN, LOCALLY, MACROLET, SYMBOL-MACROLET and the expansions of
the page's own defining macros, and the names it declaims inline."
  (let ((names '()))
    (labels ((walk (form depth)
               (when (and (consp form) (symbolp (car form)) (< depth 20))
                 (let ((op (car form)))
                   (cond ((member op '(progn locally)) (dolist (f (cdr form)) (walk f depth)))
                         ((member op '(macrolet symbol-macrolet)) (dolist (f (cddr form)) (walk f depth)))
                         ((eq op 'eval-when) (dolist (f (cddr form)) (walk f depth)))
                         ((eq op 'declaim)
                          (dolist (spec (cdr form))
                            (when (and (consp spec) (eq (car spec) 'inline))
                              (dolist (n (cdr spec)) (push n names)))))
                         ((member op '(defun defmacro define-compiler-macro defgeneric defmethod
                                       defparameter defvar defconstant define-symbol-macro
                                       deftype))
                          (push (second form) names))
                         ((eq op 'defstruct)
                          (push (if (consp (second form)) (first (second form)) (second form)) names))
                         ((and (macro-function op) (not (eq (symbol-package op) (find-package :cl))))
                          (walk (ignore-errors (macroexpand-1 form)) (1+ depth))))))))
      (walk form 0))
    names))

(defvar *expansion-names* (make-hash-table :test #'equal)
  "Every name a form inside an EVAL-WHEN of the files defines: a function or a parameter the
compiler may call or read while it expands a macro, so that a change to it reaches the code the
macro wrote.")

(defun compile-time-forms (form text start)
  "When FORM, read from TEXT at START, is an EVAL-WHEN, each form inside it as (FORM . START),
its position in TEXT; else NIL."
  (when (and (consp form) (eq (car form) 'eval-when))
    (let ((position (nth-value 1 (read-from-string text t nil :start (1+ start))))) ; the operator
      (setf position (nth-value 1 (read-from-string text t nil :start position)))   ; its situations
      (loop for at = (physics::skip-blanks-and-comments text position)
            until (char= (char text at) #\))
            collect (multiple-value-bind (inner end) (read-from-string text t nil :start at)
                      (setf position end)
                      (cons inner at))))))

(defun make-form-unit (form file line anchors)
  "The UNIT of FORM, a toplevel form of FILE (or one inside a toplevel EVAL-WHEN) at LINE."
  (let* ((definition (first (physics::toplevel-definitions form)))
         (symbols (make-hash-table :test #'eq)))
    (map-tree-symbols (lambda (s) (setf (gethash s symbols) t)) form)
    (make-unit :form form :file file :line line :anchor (aref anchors (1- line))
               :package *package*
               :name (and definition (physics::definition-name
                                      (intern (symbol-name (car definition)) :keyword)
                                      definition))
               :kind (and definition (car definition))
               :symbols symbols
               :defines (defined-names form)
               :mutable (and definition (eq definition form)
                             (member file *engine-files* :test #'string=)
                             (engine-defining-operator-p (car form))))))

(defun read-units (file)
  "The toplevel forms of FILE, each a UNIT, in order; a toplevel EVAL-WHEN gives a unit for each
form inside it, whose names go into *EXPANSION-NAMES*."
  (let* ((text (physics::read-file-text file))
         (lines (physics::split-lines text))
         (anchors (physics::line-anchors lines))
         (*package* (find-package '#:cl-user))
         (*read-eval* t)
         (units '()) (position 0) (line 1))
    (loop
      (let ((start (physics::skip-blanks-and-comments text position)))
        (when (>= start (length text)) (return (nreverse units)))
        (incf line (count #\Newline text :start position :end start))
        (multiple-value-bind (form end) (read-from-string text t nil :start start)
          (when (and (consp form) (eq (car form) 'in-package))
            (setf *package* (find-package (second form))))
          (let ((inner (compile-time-forms form text start)))
            (if inner
                (loop for (f . at) in inner
                      for unit = (make-form-unit f file (+ line (count #\Newline text :start start :end at))
                                                 anchors)
                      do (dolist (n (unit-defines unit)) (setf (gethash n *expansion-names*) t))
                         (push unit units))
                (push (make-form-unit form file line anchors) units)))
          (incf line (count #\Newline text :start start :end end))
          (setf position end))))))

;;; ------------------------------------------------------------------------------------
;;; Who must be compiled again: inlined functions, macros, and what they generate

(defvar *inline-names* (make-hash-table :test #'equal)
  "Every name some form of the files declares or declaims inline, even where a later
declamation makes it not inline by default: callers may still ask for it.")

(defun note-inline-names (units)
  "Fill *INLINE-NAMES* from the (INLINE name...) specifiers anywhere in UNITS' forms."
  (dolist (u units)
    (labels ((walk (x)
               (when (consp x)
                 (when (and (eq (car x) 'inline) (proper-list-p x))
                   (dolist (n (cdr x)) (when (symbolp n) (setf (gethash n *inline-names*) t))))
                 (when (proper-list-p x) (mapc #'walk x)))))
      (walk (unit-form u)))))

(defun inlined-name-p (name)
  "True if a change to NAME's definition reaches the code of its callers: a macro, a
compiler macro, a symbol macro, a function declared inline, a definition of an EVAL-WHEN that
a macro may call while it expands, or a featured kernel, whose text define-impact-copy
compiles again under another name."
  (and (symbolp name)
       (or (gethash name *inline-names*)
           (gethash name *expansion-names*)
           (get name 'physics::featured-kernel)
           (and (fboundp name) (macro-function name))
           (compiler-macro-function name)
           (eq (sb-int:info :function :inlinep name) 'inline)
           (eq (sb-int:info :variable :kind name) :macro))))

(defun dependents (unit units)
  "The units other than UNIT that must be evaluated again after UNIT is: those mentioning a
name UNIT defines that is inlined or expanded, and so on transitively; in file order."
  (let ((pending (remove-if-not #'inlined-name-p (unit-defines unit)))
        (done (make-hash-table :test #'eq))
        (chosen (make-hash-table :test #'eq)))
    (loop while pending
          do (let ((name (pop pending)))
               (unless (gethash name done)
                 (setf (gethash name done) t)
                 (dolist (u units)
                   (when (and (not (eq u unit)) (not (gethash u chosen))
                              (gethash name (unit-symbols u))
                              (not (member name (unit-defines u))))
                     (setf (gethash u chosen) t)
                     (dolist (n (unit-defines u))
                       (when (inlined-name-p n) (push n pending))))))))
    (remove-if-not (lambda (u) (gethash u chosen)) units)))

;;; ------------------------------------------------------------------------------------
;;; Operators.  A site is (OPERATOR FROM TO REBUILD): REBUILD returns the whole toplevel form
;;; with TO in place of FROM.

(defparameter *comparison-flips*
  '((< . <=) (<= . <) (> . >=) (>= . >) (= . /=) (/= . =) (min . max) (max . min)
    (plusp . minusp) (minusp . plusp))
  "Comparison flips: a boundary moved, an equality negated, a bound of the other side.")

(defparameter *commutative* '(+ * = /= max min logand logior logxor eq eql equal and or list
                              values vector)
  "Operators whose arguments are not swapped: the swap means the same thing, or lists data.")

(defparameter *body-operators* '(progn when unless let let* dolist dotimes multiple-value-bind
                                 flet labels lambda defun defmethod defmacro locally
                                 destructuring-bind)
  "Operators with a body whose statements may be dropped: the forms of a WHEN or UNLESS, and
the forms before the last of the others.")

(defparameter *type-operators* '(declare declaim deftype check-type quote function
                                 in-package sb-ext:truly-the)
  "Forms not walked: types, declarations and literal data.")

(defvar *sites*)

(defvar *unit-symbols* (make-hash-table :test #'eq)
  "The symbols the toplevel form being walked mentions: a wrong variable is one of them.")

(defvar *layouts* '()
  "Each columnar layout's name with its columns, (COLUMN TYPE [WIDTH]) in declaration order, as
the page's define-physics-layout forms declare them.")

(defun site (operator from to rebuild)
  (push (list operator from to rebuild) *sites*))

(defun starts-with-name-p (prefix symbol)
  (and (symbolp symbol) (physics::starts-with prefix (symbol-name symbol))))

(defparameter *token-families* '("XYZ" "AB" "IJK" "123")
  "Letters or digits that name one of a family: an axis, a side of a pair, an index, a tangent.")

(defun token-siblings (token)
  "The tokens that differ from TOKEN in its last character within one family: x for y, vz for vx,
ima for imb, t1x for t1y, l2 for l1.  Only short tokens (four characters at most), which are
names of that kind rather than words that happen to end in such a letter."
  (let ((n (length token)))
    (when (<= 1 n 4)
      (let* ((last (char token (1- n)))
             (family (find-if (lambda (f) (find last f)) *token-families*)))
        (when family
          (loop for c across family
                unless (char= c last)
                  collect (concatenate 'string (subseq token 0 (1- n)) (string c))))))))

(defun variable-siblings (symbol)
  "The variables of the form being walked whose names differ from SYMBOL's in one token of a
family: the same kind of value read from the wrong axis, side or index."
  (let* ((tokens (uiop:split-string (symbol-name symbol) :separator "-"))
         (siblings '()))
    (loop for i from 0 below (length tokens)
          do (dolist (new (token-siblings (nth i tokens)))
               (let ((s (find-symbol (format nil "~{~A~^-~}" (replace-nth tokens i new))
                                     (symbol-package symbol))))
                 (when (and s (not (eq s symbol)) (variable-symbol-p s) (gethash s *unit-symbols*))
                   (pushnew s siblings)))))
    (nreverse siblings)))

(defun neighbour-columns (column columns)
  "The columns declared just before and just after COLUMN among COLUMNS, ((NAME TYPE ...) ...),
that have its type and width: a wrong column of the same layout."
  (let* ((spec (find (symbol-name column) columns :key (lambda (c) (symbol-name (first c))) :test #'string=))
         (same (and spec (remove-if-not (lambda (c) (equal (rest c) (rest spec))) columns)))
         (at (and spec (position spec same))))
    (when at
      (remove nil (list (and (> at 0) (first (nth (1- at) same)))
                        (and (< (1+ at) (length same)) (first (nth (1+ at) same))))))))

(defun unit-layouts (units)
  "Each layout the define-physics-layout forms of UNITS declare, as (NAME COLUMN...)."
  (loop for u in units
        for form = (unit-form u)
        when (and (consp form) (starts-with-name-p "DEFINE-PHYSICS-LAYOUT" (car form)))
          collect (cons (second form) (nthcdr 3 form))))

(defun layout-of-macro (operator)
  "The layout whose WITH- macro OPERATOR is, if it is one."
  (and (starts-with-name-p "WITH-" operator)
       (find (subseq (symbol-name operator) 5) *layouts* :key (lambda (l) (symbol-name (car l))) :test #'string=)))

(defun layout-accessor (operator)
  "If OPERATOR reads a column of a layout, (LAYOUT . COLUMN)."
  (and (symbolp operator)
       (loop for (layout . columns) in *layouts*
             for prefix = (concatenate 'string (symbol-name layout) "-")
             for column = (and (physics::starts-with prefix (symbol-name operator))
                               (find (subseq (symbol-name operator) (length prefix)) columns
                                     :key (lambda (c) (symbol-name (first c))) :test #'string=))
             when column return (cons layout (first column)))))

(defun constraint-columns ()
  "The constraint block's columns, main then side, each (NAME FLOAT) with the block it lies in,
and the second names of +constraint-column-aliases+, neighbours among themselves."
  (append (mapcar (lambda (c) (list c 'main)) physics::+constraint-columns+)
          (mapcar (lambda (c) (list c 'side)) physics::+constraint-side-columns+)
          (mapcar (lambda (a) (list (car a) 'alias)) physics::+constraint-column-aliases+)))

(defun check-form-p (form)
  "True if FORM checks an argument or a state: a call of the page's CHECK-... or REQUIRE-...
functions, an ERROR, SIGNAL, ASSERT or CHECK-TYPE, or a WHEN or UNLESS whose body is such."
  (and (consp form) (symbolp (car form))
       (or (member (car form) '(error cerror signal assert check-type))
           (starts-with-name-p "CHECK-" (car form))
           (starts-with-name-p "REQUIRE-" (car form))
           (and (member (car form) '(when unless)) (proper-list-p form)
                (some #'check-form-p (cddr form))))))

(defun variable-symbol-p (x)
  (and (symbolp x) x (not (eq x t)) (not (keywordp x)) (not (constantp x))))

(defun same-kind-p (a b)
  "True if A and B are worth swapping: two variables, or two different numbers of one type."
  (or (and (variable-symbol-p a) (variable-symbol-p b) (not (eq a b)))
      (and (numberp a) (numberp b) (eq (type-of a) (type-of b)) (/= a b))))

(defun replace-nth (list n new)
  (append (subseq list 0 n) (list new) (nthcdr (1+ n) list)))

(defun remove-nth (list n)
  (append (subseq list 0 n) (nthcdr (1+ n) list)))

(defun proper-list-p (x)
  (handler-case (list-length x) (error () nil)))

(defun walk (x rebuild &optional parent index)
  "Collect the sites of the evaluated form X, which REBUILD puts back into the toplevel form.
PARENT, if given, is the list holding X at INDEX; a literal's site shows it."
  (flet ((literal (operator new)
           (site operator (or parent x) (if parent (replace-nth parent index new) new)
                 (lambda () (funcall rebuild new)))))
    (cond ((comma-p x)
           (walk (sb-impl::comma-expr x)
                 (lambda (new) (funcall rebuild (sb-impl::unquote new (sb-impl::comma-kind x))))))
          ((variable-symbol-p x)
           ;; shown in its call, with the arguments before and after it elided, so that two
           ;; mutants of one call are told apart
           (dolist (other (variable-siblings x))
             (let ((other other))
               (flet ((text (v)
                        (if (and parent (symbolp (car parent)))
                            (let ((*print-case* :downcase))
                              (format nil "(~S ~:[~;... ~]~S~:[~; ...~])" (car parent) (> index 1) v
                                      (< (1+ index) (length parent))))
                            (string-downcase (symbol-name v)))))
                 (site "wrong variable" (text x) (text other) (lambda () (funcall rebuild other)))))))
          ((typep x 'integer)
           (literal "off-by-one" (1+ x))
           (literal "off-by-one" (1- x)))
          ((typep x 'float)
           ;; an infinity, or a literal whose double or half overflows, is only scaled
           ;; where the result is still a float
           (unless (or (zerop x) (sb-ext:float-infinity-p x) (sb-ext:float-nan-p x))
             (dolist (scaled (list (ignore-errors (* x 2)) (ignore-errors (/ x 2))))
               (when (and scaled (not (sb-ext:float-infinity-p scaled)) (not (zerop scaled)))
                 (literal "constant scaling" scaled)))
             (literal "sign flip" (- x))))
          ((and (consp x) (proper-list-p x))
           (walk-call x rebuild)))))

(defun walk-elements (x rebuild start &optional end)
  "Walk elements START to END of the list X as evaluated forms."
  (loop for i from start below (or end (length x))
        do (let ((i i))
             (walk (nth i x) (lambda (new) (funcall rebuild (replace-nth x i new))) x i))))

(defun drop-sites (x rebuild start every)
  "Dropped-form sites for the body of X that starts at START: every form if EVERY, else all
but the last.  Declarations and docstrings stay."
  (let ((n (length x)))
    (loop for i from start below (if every n (1- n))
          for form = (nth i x)
          unless (or (stringp form) (and (consp form) (eq (car form) 'declare)) (atom form))
            do (site (if (check-form-p form) "dropped check" "dropped form") form :dropped
                     (let ((i i)) (lambda () (funcall rebuild (remove-nth x i))))))))

(defun walk-bindings (x index rebuild)
  "Walk the init forms of the binding list at INDEX of X (LET, LET*)."
  (let ((bindings (nth index x)))
    (when (proper-list-p bindings)
      (loop for j from 0 below (length bindings)
            for b = (nth j bindings)
            when (and (consp b) (cdr b))
              do (let ((j j) (b b))
                   (walk (second b)
                         (lambda (new)
                           (funcall rebuild
                                    (replace-nth x index
                                                 (replace-nth bindings j (list (first b) new)))))))))))

(defun walk-call (x rebuild)
  (let ((op (car x)) (n (length x)))
    (flet ((swap-operator (operator new)
             (let ((new (cons new (cdr x))))
               (site operator x new (lambda () (funcall rebuild new)))))
           (body (start)
             (walk-elements x rebuild start)
             (when (member op *body-operators*)
               (drop-sites x rebuild start (member op '(when unless))))))
      (cond
        ((not (symbolp op))
         (when (and (consp op) (eq (car op) 'lambda)) (walk op (lambda (new) (funcall rebuild (cons new (cdr x))))))
         (walk-elements x rebuild 1))
        ((member op *type-operators*))
        ;; a type, or a prototype that only names a type, is not mutated
        ((member op '(the coerce typep float)) (walk-elements x rebuild (if (eq op 'the) 2 1) (if (eq op 'the) 3 2)))
        ((eq op 'sb-int:quasiquote) (walk-elements x rebuild 1))
        ((eq op 'loop)
         ;; a variable a clause binds, and a type, are not read: what follows FOR, AS, WITH,
         ;; INTO, NAMED and OF-TYPE is left alone
         (loop for i from 1 below n
               unless (member (nth (1- i) x) '(for as with into named of-type)
                              :test (lambda (a b) (and (symbolp a) (string= (symbol-name a) (symbol-name b)))))
                 do (let ((i i)) (walk (nth i x) (lambda (new) (funcall rebuild (replace-nth x i new))) x i))))
        ((and (symbolp op) (member (symbol-name op) (quote ("@" "@W")) :test (function string=)) (= n 2) (symbolp (second x)))
         ;; (@ COLUMN) reads a constraint column: a wrong column is its neighbour in the block
         (dolist (other (neighbour-columns (second x) (constraint-columns)))
           (let ((new (list op (intern (symbol-name other) *package*))))
             (site "wrong column" x new (lambda () (funcall rebuild new))))))
        ((and (layout-of-macro op) (>= n 3) (proper-list-p (second x)))
         ;; (WITH-LAYOUT (SPEC...) BUFFER . BODY): a spec, NAME or (VARIABLE COLUMN), may bind the
         ;; neighbouring column of the layout instead
         (let ((columns (cdr (layout-of-macro op))) (specs (second x)))
           (loop for j from 0 below (length specs)
                 for spec = (nth j specs)
                 for variable = (if (consp spec) (first spec) spec)
                 for column = (if (consp spec) (second spec) spec)
                 when (and (symbolp variable) (symbolp column))
                   do (dolist (other (neighbour-columns column columns))
                        (let* ((other (intern (symbol-name other) *package*))
                               (new (replace-nth x 1 (replace-nth specs j (list variable other)))))
                          (site "wrong column" spec (list variable other)
                                (lambda () (funcall rebuild new)))))))
         (walk-elements x rebuild 2))
        ((and (eq op 'if) (= n 4) (or (check-form-p (third x)) (check-form-p (fourth x))))
         ;; a test whose branch signals is a check: dropping it keeps the other branch
         (let ((kept (if (check-form-p (third x)) (fourth x) (third x))))
           (site "dropped check" x kept (lambda () (funcall rebuild kept))))
         (walk-elements x rebuild 1))
        ((member op '(defun defmacro)) (body 3))
        ((eq op 'defmethod)
         (let ((args (position-if #'listp x :start 2))) (when args (body (1+ args)))))
        ((eq op 'defparameter) (walk (third x) (lambda (new) (funcall rebuild (replace-nth x 2 new)))))
        ((eq op 'lambda) (body 2))
        ((member op '(let let*)) (walk-bindings x 1 rebuild) (body 2))
        ((member op '(flet labels macrolet))
         (let ((defs (second x)))
           (when (proper-list-p defs)
             (loop for j from 0 below (length defs)
                   for d = (nth j defs)
                   when (and (consp d) (proper-list-p d))
                     do (let ((j j) (d d))
                          (walk-elements d (lambda (new) (funcall rebuild (replace-nth x 1 (replace-nth defs j new))))
                                         2)))))
         (body 2))
        ((member op '(dolist dotimes))
         (let ((spec (second x)))
           (when (and (consp spec) (proper-list-p spec))
             (walk-elements spec (lambda (new) (funcall rebuild (replace-nth x 1 new))) 1)))
         (body 2))
        ((member op '(multiple-value-bind destructuring-bind))
         (walk-elements x rebuild 2 3) (body 3))
        ((member op '(typecase etypecase ctypecase case ecase ccase handler-case))
         (walk (second x) (lambda (new) (funcall rebuild (replace-nth x 1 new))))
         (loop for j from 2 below n
               for clause = (nth j x)
               when (and (consp clause) (proper-list-p clause))
                 do (let ((j j) (clause clause))
                      (walk-elements clause (lambda (new) (funcall rebuild (replace-nth x j new)))
                                     (if (eq op 'handler-case) 2 1)))))
        ((eq op 'cond)
         (loop for j from 1 below n
               for clause = (nth j x)
               when (and (consp clause) (proper-list-p clause))
                 do (let ((j j) (clause clause))
                      (when (and (rest clause) (some #'check-form-p (rest clause)))
                        (let ((new (remove-nth x j)))
                          (site "dropped check" clause :dropped (lambda () (funcall rebuild new)))))
                      (walk-elements clause (lambda (new) (funcall rebuild (replace-nth x j new))) 0))))
        (t
         (when (and (string= (symbol-name op) "RANGED-F32") (>= n 5))
           ;; a value checked against a range is checked only for being a finite number
           (let ((new (list* (intern "FINITE-F32" (symbol-package op)) (second x) (third x) (nthcdr 5 x))))
             (site "dropped check" x new (lambda () (funcall rebuild new)))))
         (let ((column (layout-accessor op)))
           (when (and column (= n 2))
             (dolist (other (neighbour-columns (cdr column) (cdr (assoc (car column) *layouts*))))
               (let ((new (list (intern (format nil "~A-~A" (car column) other) (symbol-package op)) (second x))))
                 (site "wrong column" x new (lambda () (funcall rebuild new)))))))
         (let ((flip (cdr (assoc op *comparison-flips*))))
           (when flip (site "comparison flip" x (cons flip (cdr x)) (lambda () (funcall rebuild (cons flip (cdr x)))))))
         (case op
           (+ (when (>= n 3) (swap-operator "sign flip" '-)))
           (- (if (= n 2)
                  (site "sign flip" x (second x) (lambda () (funcall rebuild (second x))))
                  (swap-operator "sign flip" '+)))
           (incf (swap-operator "sign flip" 'decf))
           (decf (swap-operator "sign flip" 'incf))
           (1+ (swap-operator "off-by-one" '1-))
           (1- (swap-operator "off-by-one" '1+)))
         (when (and (fboundp op) (not (macro-function op)) (not (special-operator-p op))
                    (not (member op *commutative*)) (>= n 3))
           (loop for i from 1 below (1- n)
                 when (same-kind-p (nth i x) (nth (1+ i) x))
                   do (let ((i i))
                        (let ((new (replace-nth (replace-nth x i (nth (1+ i) x)) (1+ i) (nth i x))))
                          (flet ((text (a b)
                                   (let ((*print-case* :downcase) (*print-pretty* t) (*print-right-margin* 100000)
                                         (*print-length* 4) (*print-level* 2))
                                     (format nil "(~S ~:[~;... ~]~S ~S~:[~; ...~])" op (> i 1) a b (< (+ i 2) n)))))
                            (site "swapped arguments" (text (nth i x) (nth (1+ i) x)) (text (nth (1+ i) x) (nth i x))
                                  (lambda () (funcall rebuild new))))))))
         (walk-elements x rebuild 1)
         (when (member op *body-operators*) (drop-sites x rebuild 1 (member op '(when unless)))))))))

(defun unit-sites (unit)
  "Every site of UNIT's form, each (OPERATOR FROM TO REBUILD), in a fixed order."
  (let ((*sites* '()) (*package* (unit-package unit)) (*unit-symbols* (unit-symbols unit)))
    (walk (unit-form unit) (lambda (new) new))
    (nreverse *sites*)))

;;; ------------------------------------------------------------------------------------
;;; Parts of the page: the level-1 heading of each anchor, with four parts named apart

(defparameter *named-parts*
  '(("P5SOLV" . "solver") ("P4CONT" . "contact phases") ("QKS4GZ" . "sleep")
    ("D9W4CH" . "hash") ("Y5H8KC" . "hash")
    ("MYWH16" . "terrain contacts") ("MYWGTH" . "terrain contacts") ("MYWCNT" . "terrain contacts")
    ("MYWSTG" . "terrain contacts") ("SW33P7" . "terrain contacts")
    ("E7V3NT" . "events") ("H7P4CX" . "walker"))
  "Anchors whose sections, or whose part's sections, form a part named here; any other section
belongs to the part of its level-1 heading.")

(defun anchor-parts (page)
  "A hash table from each anchor of PAGE to the name of its part."
  (let ((parts (make-hash-table :test #'equal))
        (heading nil) (level 0) (part-anchor nil) (part-title nil))
    (with-open-file (in page :external-format :utf-8)
      (loop for line = (read-line in nil) while line
            do (cond ((and (plusp (length line)) (char= (char line 0) #\*))
                      (setf level (or (position #\Space line) 0)
                            heading (string-trim " " (subseq line level)))
                      (let ((tag (search "   :" heading))) (when tag (setf heading (string-trim " " (subseq heading 0 tag))))))
                     ((physics::starts-with ":CUSTOM_ID:" (string-trim " " line))
                      (let ((anchor (string-trim " " (subseq (string-trim " " line) 11))))
                        (when (= level 1) (setf part-anchor anchor part-title heading))
                        (setf (gethash anchor parts)
                              (or (cdr (assoc anchor *named-parts* :test #'string=))
                                  (cdr (assoc part-anchor *named-parts* :test #'string=))
                                  part-title)))))))
    parts))

;;; ------------------------------------------------------------------------------------
;;; Running the claims: the first failure ends the run

(defun run-claim (name)
  "Run claim NAME.  NIL if it passed; else a line saying how it failed."
  (let ((5am:*on-error* :debug) (5am:*on-failure* :debug)
        (5am:*test-dribble* (make-broadcast-stream)))
    (block claim
      (handler-bind ((5am::check-failure
                       (lambda (c) (return-from claim
                                     (format nil "~A" (or (5am::reason c) (5am::test-expr c))))))
                     (serious-condition
                       (lambda (c) (return-from claim
                                     (format nil "~A: ~A" (type-of c) c)))))
        (let ((results (5am:run name)))
          (cond ((null results) "made no check")
                ((every #'5am::test-passed-p results) nil)
                (t "failed")))))))

(defun one-line (string &optional (limit 100))
  (let ((s (substitute #\Space #\Newline (princ-to-string string))))
    (if (> (length s) limit) (concatenate 'string (subseq s 0 (- limit 3)) "...") s)))

(defun time-claims (claims)
  "Run each claim of CLAIMS, (ANCHOR . NAME), once on the unchanged engine.  Return those that
pass, cheapest first, each (NAME . SECONDS), and the names of those that fail."
  (let ((timed '()) (failing '()))
    (dolist (claim claims)
      (let* ((start (get-internal-real-time))
             (why (run-claim (cdr claim)))
             (seconds (/ (- (get-internal-real-time) start) internal-time-units-per-second)))
        (if why
            (push (cdr claim) failing)
            (push (cons (cdr claim) (float seconds 1d0)) timed))))
    (values (stable-sort (nreverse timed) #'< :key #'cdr) (nreverse failing))))

;;; ------------------------------------------------------------------------------------
;;; Which claims reach which definitions

(defvar *reached* (make-hash-table :test #'equal :synchronized t)
  "The function names called since the table was last cleared, while probes are set.")

(defun probed-names (units)
  "The function names the UNITS define that a probe can watch: functions and generic
functions of the page, not macros, not the standard's own."
  (remove-duplicates
   (loop for u in units
         append (remove-if-not
                 (lambda (n)
                   (and (or (and (symbolp n) (not (eq (symbol-package n) (find-package :cl)))
                                 (not (macro-function n)) (not (special-operator-p n)))
                            (and (consp n) (eq (car n) 'setf) (symbolp (second n))
                                 (not (eq (symbol-package (second n)) (find-package :cl)))))
                        (fboundp n)))
                 (unit-defines u)))
   :test #'equal))

(defun claims-reach (order names)
  "For each claim of ORDER, (NAME . SECONDS), the list of NAMES its run calls, found by
running it once more with every one of NAMES wrapped in a probe.  A featured kernel a world
runs as a variant compiled for its features is called through the variant, not its name: the
claim reaches the kernel when it asks featured-kernel for one."
  (dolist (n names)
    (let ((n n))
      (sb-int:encapsulate n 'mutate-reach
                          (lambda (f &rest args) (setf (gethash n *reached*) t) (apply f args)))))
  (sb-int:encapsulate 'physics::featured-kernel 'mutate-reach-variant
                      (lambda (f name &rest args) (setf (gethash name *reached*) t) (apply f name args)))
  (unwind-protect
       (loop for (claim) in order
             collect (progn (clrhash *reached*)
                            (run-claim claim)
                            (cons claim (loop for n being the hash-keys of *reached* collect n))))
    (sb-int:unencapsulate 'physics::featured-kernel 'mutate-reach-variant)
    (dolist (n names) (sb-int:unencapsulate n 'mutate-reach))))

(defun claims-reach-in-child (claims names path)
  "Fork a child that finds, as CLAIMS-REACH does, the NAMES each of CLAIMS (ANCHOR . NAME)
calls, and writes them to PATH; return its process id.  The parent meanwhile times the claims
on the other core."
  (finish-output *standard-output*) (finish-output *error-output*)
  (let ((pid (sb-posix:fork)))
    (when (zerop pid)
      (let ((null (sb-posix:open "/dev/null" sb-posix:o-rdwr)))
        (sb-posix:dup2 null 1) (sb-posix:dup2 null 2))
      (let ((*standard-output* (make-broadcast-stream)) (*error-output* (make-broadcast-stream))
            (reach (claims-reach (mapcar (lambda (c) (cons (cdr c) 0)) claims) names)))
        (with-open-file (out (format nil "~A.tmp" path) :direction :output :if-exists :supersede)
          (with-standard-io-syntax
            (let ((*package* (find-package :keyword)))
              (prin1 reach out))))
        (rename-file (format nil "~A.tmp" path) path)
        (sb-ext:exit :code 0 :abort t)))
    pid))

(defun read-reach (pid path order)
  "Wait for the child PID, and return what it wrote to PATH for the claims of ORDER."
  (sb-posix:waitpid pid 0)
  (let ((reach (with-open-file (in path)
                 (with-standard-io-syntax
                   (let ((*package* (find-package :keyword))) (read in))))))
    (ignore-errors (delete-file path))
    (remove-if-not (lambda (r) (assoc (car r) order)) reach)))

(defvar *slow* 0.05
  "The share of all the claims' time on the unchanged engine above which one claim is a
campaign: it runs only against mutants of its own part.  A share, not seconds, so that the
same claims are campaigns at any load.")

(defvar *claims-seconds* 1d0 "All the passing claims' time on the unchanged engine.")

(defvar *parts* (make-hash-table :test #'equal) "Anchor to part, as ANCHOR-PARTS gives it.")

(defvar *claim-anchors* (make-hash-table :test #'eq) "Claim name to its section's anchor.")

(defun within-reach-of-time (claims unit)
  "CLAIMS, each (NAME . SECONDS), without the campaigns of other parts than UNIT's."
  (let ((part (gethash (unit-anchor unit) *parts*)))
    (remove-if (lambda (claim)
                 (and (> (cdr claim) (* *slow* *claims-seconds*))
                      (not (equal part (gethash (gethash (car claim) *claim-anchors*) *parts*)))))
               claims)))

(defun claims-for (unit units order reach probed)
  "The claims of ORDER that can observe a mutant of UNIT: those that call a function defined
by UNIT or by a form compiled again with it, or, for a parameter, by a form that reads it, and
those whose own text mentions one of those names.  All of ORDER if none of those functions is
watched by a probe."
  (let* ((touched (cons unit (dependents unit units)))
         (touched (if (eq (unit-kind unit) 'defparameter)
                      (append touched (remove-if-not (lambda (u) (gethash (unit-name unit) (unit-symbols u))) units))
                      touched))
         (names (remove-duplicates (loop for u in touched append (unit-defines u)) :test #'equal))
         (watched (intersection names probed :test #'equal)))
    (if (null watched)
        order
        (remove-if-not (lambda (claim)
                         (or (intersection watched (cdr (assoc (car claim) reach)) :test #'equal)
                             (some (lambda (u) (and (eq (unit-kind u) 'luv-physics-tests:define-claim)
                                                    (eq (third (unit-form u)) (car claim))))
                                   touched)
                             ;; a claim that names a definition without calling it, as one that
                             ;; reads a kernel's docstring or text does
                             (let ((u (find-if (lambda (u) (and (eq (unit-kind u) 'luv-physics-tests:define-claim)
                                                               (eq (third (unit-form u)) (car claim))))
                                               units)))
                               (and u (some (lambda (n) (and (symbolp n) (gethash n (unit-symbols u)))) names)))))
                       order))))

;;; ------------------------------------------------------------------------------------
;;; A mutant and its child

(defstruct mutant
  unit operator from to rebuild index claims
  status claim reason seconds
  (compile-seconds 0d0)   ; how long its child took to evaluate it and what depends on it
  (claims-run 0))         ; how many claims its child started

(defun show (unit x &optional (limit 60))
  (cond
    ((eq x :dropped) "nothing")
    ((stringp x) x)
    (t
      (let ((*package* (unit-package unit)) (*print-pretty* t) (*print-right-margin* 100000)
            (*print-length* 5) (*print-level* 3) (*print-case* :downcase))
        (one-line (prin1-to-string x) limit)))))

(defun unit-key-name (u)
  "How the log, the report and the page name unit U: its name on one line, in lower case, whole
(a featured kernel's name holds its feature list, longer than a line)."
  (let ((*package* (unit-package u)) (*print-pretty* nil))
    (string-downcase (prin1-to-string (unit-name u)))))

(defun mutant-key (m)
  "How the report and the page name mutant M: DEFINITION: FROM => TO."
  (let ((u (mutant-unit m)))
    (format nil "~A: ~A => ~A" (unit-key-name u) (show u (mutant-from m)) (show u (mutant-to m)))))

(defun evaluate-in-child (mutant units)
  "Evaluate MUTANT's definition, then every unit that inlines it or is generated from it.
NIL if all compiled without a warning; else a line saying what went wrong."
  (let* ((unit (mutant-unit mutant))
         (forms (cons (cons unit (funcall (mutant-rebuild mutant)))
                      (mapcar (lambda (u) (cons u (unit-form u))) (dependents unit units))))
         (texts (featured-texts)))
    ;; a kernel whose defining form is evaluated again keeps the text that form keeps, or none
    (loop for (name) in texts
          when (some (lambda (f) (member name (unit-defines (car f)))) forms)
            do (remprop name 'physics::featured-kernel))
    (block compile
      (handler-bind ((style-warning #'muffle-warning)
                     (warning (lambda (w) (return-from compile (format nil "warning: ~A" w))))
                     (serious-condition (lambda (c) (return-from compile (format nil "~A: ~A" (type-of c) c)))))
        (let ((*compile-verbose* nil) (*compile-print* nil) (sb-ext:*evaluator-mode* :compile))
          (loop for (u . form) in forms
                do (let ((*package* (unit-package u)))
                     ;; a definition the mutant drops is gone, as from an image that loaded the
                     ;; mutated page, and not left as the unchanged engine defined it: one dropped
                     ;; from the mutated form, or from the expansion, by a mutated macro evaluated
                     ;; before it, of a form evaluated again with it
                     (dolist (name (set-difference (unit-defines u) (defined-names form) :test #'equal))
                       (when (and (or (symbolp name) (and (consp name) (eq (car name) 'setf)))
                                  (fboundp name) (not (typep (fdefinition name) 'generic-function))
                                  (not (and (symbolp name) (special-operator-p name))))
                         (fmakunbound name))))
                   (let ((*package* (unit-package u))
                         (inline (remove-if-not (lambda (n) (and (symbolp n) (gethash n *inline-names*)))
                                                (unit-defines u))))
                     ;; a function declared inline only around its definition keeps its
                     ;; expansion only if it is inline while the definition is evaluated
                     (let ((saved (mapcar (lambda (n) (sb-int:info :function :inlinep n)) inline)))
                       (when inline (proclaim `(inline ,@inline)))
                       (eval form)
                       (loop for n in inline for was in saved
                             do (setf (sb-int:info :function :inlinep n) was)))))
          (renew-featured-variants (mapcar #'car forms) texts))
        nil))))

;;; The variants of the featured kernels ([[#KTXT7V]], [[#FEAT5X]]) are compiled from a kernel's
;;; text, kept on its name's plist, and held in physics::*featured-kernels*: those of the
;;; standard feature sets since the page was loaded, the others since a claim first asked for
;;; them, in this image before it forked.  Evaluating a mutant again does not touch that table.

(defvar *precompiled-variants* '()
  "The keys (NAME . FEATURES) the table of variants held when the engine was loaded, before any
claim ran: the variants compiled with the page.")

(defun featured-texts ()
  "Each featured kernel's name with the text it keeps now, for every name in the table of variants."
  (let ((names '()))
    (maphash (lambda (key function) (declare (ignore function)) (pushnew (car key) names))
             physics::*featured-kernels*)
    (mapcar (lambda (name) (cons name (get name 'physics::featured-kernel))) names)))

(defun renew-featured-variants (evaluated texts)
  "After the forms EVALUATED (units) were evaluated again, compile again every variant held in the
table whose kernel's text was replaced (TEXTS holds each name's text from before), the variant
compiled with the page and those the claims compiled alike, so that the claims run the mutant in
every feature set; and when EVALUATED define the function that compiles variants at run time,
drop the variants it compiled, so that the mutant compiles them again as a fresh image would.
A kernel that keeps no text after them cannot have its variants compiled, as the page could not
be loaded: that is an error.  Return the number of variants compiled again."
  (loop for (name) in texts
        unless (get name 'physics::featured-kernel)
          do (error "the featured kernel ~(~A~) keeps no text to compile its variants from" name))
  (let ((stale '())
        (builder (some (lambda (u) (member 'physics::featured-kernel (unit-defines u))) evaluated)))
    (maphash (lambda (key function)
               (declare (ignore function))
               (let ((before (assoc (car key) texts)))
                 (cond ((and before (not (eq (cdr before) (get (car key) 'physics::featured-kernel))))
                        (push key stale))
                       ((and builder (not (member key *precompiled-variants* :test #'equal)))
                        (remhash key physics::*featured-kernels*)))))
             physics::*featured-kernels*)
    (dolist (key stale)
      (remhash key physics::*featured-kernels*)
      (let ((*package* (find-package '#:luv-physics)))
        (setf (gethash key physics::*featured-kernels*)
              (funcall (compile nil `(lambda () ,(physics::featured-kernel-form (car key) (cdr key))))))))
    (length stale)))

(defun child (mutant units order status-path)
  "The body of a forked child: compile MUTANT, then run the claims of ORDER until one fails,
writing each step to STATUS-PATH.  Never returns."
  (let ((null (sb-posix:open "/dev/null" sb-posix:o-rdwr)))
    (sb-posix:dup2 null 1) (sb-posix:dup2 null 2))
  (let ((*standard-output* (make-broadcast-stream)) (*error-output* (make-broadcast-stream))
        (*trace-output* (make-broadcast-stream)))
    (with-open-file (out status-path :direction :output :if-exists :supersede)
      (flet ((say (control &rest arguments)
               (format out "~?~%" control arguments) (finish-output out)))
        (let* ((start (now))
               (problem (evaluate-in-child mutant units)))
          (when problem
            (say "UNCOMPILABLE ~A" (one-line problem 200))
            (sb-ext:exit :code 0 :abort t))
          (say "COMPILED ~,2F" (- (now) start)))
        (dolist (claim order)
          (say "START ~A" (symbol-name (car claim)))
          (let ((why (run-claim (car claim))))
            (when why
              (say "KILLED ~A ~A" (symbol-name (car claim)) (one-line why 200))
              (sb-ext:exit :code 0 :abort t))))
        (say "SURVIVED")
        (sb-ext:exit :code 0 :abort t)))))

;;; ------------------------------------------------------------------------------------
;;; Sampling: sections round robin, each section's sites in a seeded order
;;;
;;; Each section's order comes from a random state seeded by SEED and a hash of its anchor
;;; alone, and the sections are ordered by another such hash, so that an edit of one section,
;;; which changes its sites, changes no other section's mutants or place in the draw.

(defun fnv-1a (string &optional (hash 2166136261))
  "The 32-bit FNV-1a hash of STRING's character codes, continued from HASH: a hash that,
unlike SXHASH, is the same in every image and every version of the compiler."
  (loop for c across string
        do (setf hash (ldb (byte 32 0) (* (logxor hash (char-code c)) 16777619))))
  hash)

(defun anchor-hash (seed purpose anchor)
  "A 32-bit hash of SEED, the word PURPOSE and ANCHOR, the same in every image."
  (fnv-1a anchor (fnv-1a (format nil "~D ~A " seed purpose))))

(defun section-random-state (seed anchor)
  "The random state that orders the mutants of the section ANCHOR: from SEED and ANCHOR only."
  (sb-ext:seed-random-state (anchor-hash seed "sites" anchor)))

(defun shuffle (list state)
  (let ((v (coerce list 'vector)))
    (loop for i from (1- (length v)) downto 1
          do (rotatef (aref v i) (aref v (random (1+ i) state))))
    (coerce v 'list)))

(defun operators-in-turn (mutants state)
  "MUTANTS, already in a seeded order, taken one operator at a time: the operators in a seeded
order, each giving the next of its own mutants in turn, so that a section's first mutants are of
different operators however many sites each operator has there."
  (let ((groups (shuffle (remove-duplicates (mapcar #'mutant-operator mutants) :test #'string=) state)))
    (let ((queues (mapcar (lambda (op) (remove op mutants :key #'mutant-operator :test-not #'string=)) groups)))
      (loop while (some #'identity queues)
            append (loop for q on queues when (car q) collect (pop (car q)))))))

(defun section-sites (units anchor-filter &optional match)
  "An alist from anchor to the list of its mutants (not yet run), in file order."
  (let ((table '()))
    (dolist (u units)
      (when (and (unit-mutable u) (unit-anchor u)
                 (or (null anchor-filter)
                     (member (unit-anchor u) (uiop:split-string anchor-filter :separator "|")
                             :test #'string=)))
        (let ((entry (or (assoc (unit-anchor u) table :test #'string=)
                         (car (push (list (unit-anchor u)) table)))))
          (dolist (s (unit-sites u))
            (let ((m (make-mutant :unit u :operator (first s) :from (second s) :to (third s)
                                  :rebuild (fourth s))))
              (when (or (null match) (some (lambda (one) (search one (mutant-key m))) (uiop:split-string match :separator "|")))
                (push m (cdr entry))))))))
    (mapcar (lambda (e) (cons (car e) (nreverse (cdr e)))) (nreverse table))))

(defun drawn-sections (sections seed)
  "SECTIONS, an alist from anchor to its mutants in file order, as the draw deals from them:
each section's mutants shuffled and taken one operator at a time with its own random state
(SECTION-RANDOM-STATE), and the sections, those with a mutant, ordered by a seeded hash of
their anchors.  A section's order and its place among the others depend on SEED and its own
anchor and mutants, not on which other sections there are."
  (let ((drawn (loop for (anchor . mutants) in sections
                     for state = (section-random-state seed anchor)
                     when mutants
                       collect (cons anchor (operators-in-turn (shuffle mutants state) state)))))
    (flet ((before-p (a b)
             (let ((ha (anchor-hash seed "order" a)) (hb (anchor-hash seed "order" b)))
               (or (< ha hb) (and (= ha hb) (string< a b))))))
      (stable-sort drawn #'before-p :key #'car))))

;;; ------------------------------------------------------------------------------------
;;; The parent: two children at a time, timeouts, replacements

(defparameter *compile-timeout* 600 "Seconds a child may take to compile its mutant: a mutant of the kernel template compiles both wide families and their variants again, minutes on a loaded machine.")

(defun claim-timeout (seconds)
  "How long a claim that takes SECONDS on the unchanged engine may run in a child."
  (+ 20 (* 10 seconds)))

(defun read-status (path)
  (with-open-file (in path :if-does-not-exist nil)
    (and in (loop for line = (read-line in nil) while line collect line))))

(defun now () (/ (get-internal-real-time) (float internal-time-units-per-second 1d0)))

(defun load-average ()
  (with-open-file (in "/proc/loadavg") (read-line in)))

(defun getenv-integer (name default)
  (let ((v (sb-ext:posix-getenv name)))
    (if (and v (plusp (length (string-trim " " v)))) (parse-integer v) default)))

(defstruct job mutant pid path started claim claim-started lines)

(defun finish-job (job status claim reason)
  (let* ((m (job-mutant job))
         (lines (read-status (job-path job)))
         (compiled (find-if (lambda (l) (physics::starts-with "COMPILED " l)) lines)))
    (setf (mutant-status m) status (mutant-claim m) claim (mutant-reason m) reason
          (mutant-seconds m) (- (now) (job-started job))
          (mutant-claims-run m) (count-if (lambda (l) (physics::starts-with "START " l)) lines))
    (when compiled
      (setf (mutant-compile-seconds m)
            (let ((*read-default-float-format* 'double-float))
              (float (read-from-string (subseq compiled 9)) 1d0))))
    m))

(defun poll-job (job timeouts)
  "The mutant of JOB if its child is done (or was stopped), else NIL."
  (let* ((lines (read-status (job-path job)))
         (last (car (last lines)))
         (pid (job-pid job)))
    (when (and last (physics::starts-with "START " last) (not (equal last (job-claim job))))
      (setf (job-claim job) last (job-claim-started job) (now)))
    (multiple-value-bind (done status) (sb-posix:waitpid pid sb-posix:wnohang)
      (cond ((plusp done)
             (let ((lines (read-status (job-path job))))
               (let ((last (car (last lines))))
                 (cond ((null last) (finish-job job :crashed nil (format nil "child ended with status ~D" status)))
                       ((physics::starts-with "UNCOMPILABLE" last) (finish-job job :uncompilable nil (subseq last 13)))
                       ((physics::starts-with "KILLED " last)
                        (let* ((rest (subseq last 7))
                               (space (position #\Space rest)))
                          (finish-job job :killed (subseq rest 0 space) (if space (subseq rest (1+ space)) ""))))
                       ((string= last "SURVIVED") (finish-job job :survived nil nil))
                       (t (finish-job job :crashed (and (physics::starts-with "START " last) (subseq last 6))
                                      (format nil "child died (status ~D)" status)))))))
            (t
             (let* ((claim (job-claim job))
                    (limit (if claim
                               (claim-timeout (or (cdr (assoc (subseq claim 6) timeouts :test #'string=)) 10))
                               *compile-timeout*))
                    (since (or (job-claim-started job) (job-started job))))
               (when (> (- (now) since) limit)
                 (ignore-errors (sb-posix:kill pid sb-posix:sigkill))
                 (sb-posix:waitpid pid 0)
                 (finish-job job :timeout (and claim (subseq claim 6))
                             (format nil "no answer in ~,0F s" limit)))))))))

(defparameter *record-file* "report/mutate-claims.tsv"
  "Each claim's tries and kills over the runs so far, which order the claims of the next run.")

(defvar *record* (make-hash-table :test #'equal)
  "Claim name to (TRIES KILLS), read from *RECORD-FILE* and counted on in this run.")

(defun read-record ()
  (clrhash *record*)
  (with-open-file (in *record-file* :if-does-not-exist nil)
    (when in
      (loop for line = (read-line in nil) while line
            do (destructuring-bind (name tries kills) (uiop:split-string line :separator '(#\Tab))
                 (setf (gethash name *record*) (list (parse-integer tries) (parse-integer kills)))))))
  *record*)

(defun write-record ()
  (with-open-file (out *record-file* :direction :output :if-exists :supersede)
    (loop for (name . entry) in (sort (loop for k being the hash-keys of *record* using (hash-value v)
                                           collect (cons k v))
                                     #'string< :key #'car)
          do (format out "~A	~D	~D~%" name (first entry) (second entry)))))

(defun note-claims (record job m)
  "Count in RECORD, for each claim JOB's child started, one more try, and one more kill for
the claim that killed mutant M."
  (dolist (line (read-status (job-path job)))
    (when (physics::starts-with "START " line)
      (incf (car (or (gethash (subseq line 6) record)
                     (setf (gethash (subseq line 6) record) (list 0 0)))))))
  (when (and (eq (mutant-status m) :killed) (mutant-claim m))
    (let ((entry (or (gethash (mutant-claim m) record)
                     (setf (gethash (mutant-claim m) record) (list 1 0)))))
      (incf (second entry)))))

(defun by-promise (claims record anchor)
  "CLAIMS, each (NAME . SECONDS), in the order that stops soonest on average: first the claims
of the mutated section ANCHOR, written against its definitions, cheapest first; then the rest
by SECONDS over the share of earlier mutants the claim killed when it ran (RECORD holds its
tries and kills), with one kill in four tries granted to every claim so that an untried claim
ranks by its cost."
  (flet ((cost (claim)
           (destructuring-bind (&optional (tries 0) (kills 0))
               (gethash (symbol-name (car claim)) record)
             (/ (cdr claim) (/ (+ kills 1) (+ tries 4)))))
         (own-p (claim) (equal anchor (gethash (car claim) *claim-anchors*))))
    (let ((own (remove-if-not #'own-p claims)))
      (append (stable-sort own #'< :key #'cdr)
              (stable-sort (remove-if #'own-p claims) #'< :key #'cost)))))

(defun draw (sections count)
  "The COUNT mutants a run draws from SECTIONS, as (ANCHOR . MUTANT) in the order it draws them,
as if each compiled: slot I belongs to the section I mod the number of sections, and a section
with no mutant left gives its slot to the next that has one."
  (let* ((anchors (mapcar #'car sections))
         (queues (mapcar (lambda (s) (cons (car s) (copy-list (cdr s)))) sections)))
    (loop for i below count
          for after = (member (nth (mod i (length anchors)) anchors) anchors :test #'string=)
          for anchor = (find-if (lambda (a) (cdr (assoc a queues :test #'string=)))
                                (append after (ldiff anchors after)))
          when anchor
            collect (cons anchor (pop (cdr (assoc anchor queues :test #'string=)))))))

(defun list-draw (sections count parts)
  "Print the COUNT mutants a run would draw from SECTIONS, without running any: one line each,
with its place in the draw, its part, its section and its name."
  (loop for (anchor . m) in (draw sections count)
        for i from 1
        do (format t "~&~3D ~A | ~A | ~A | ~A~%" i (gethash anchor parts "?") anchor
                   (mutant-operator m) (mutant-key m))))

(defun run-mutants (sections count units order reach probed jobs directory report &optional only)
  "Run COUNT mutants drawn round robin from SECTIONS, JOBS at a time; call REPORT on each
finished one.  Return the finished mutants that compiled, in the order they were drawn.  ONLY,
if given, is the list of the sections' anchors, one per mutant, of the slots to run instead of
the COUNT round robin ones."
  (let* ((anchors (mapcar #'car sections))
         (queues (mapcar (lambda (s) (cons (car s) (cdr s))) sections))
         (slots '()) (running '()) (finished '()) (serial 0) (parent (sb-posix:getpid))
         (record *record*)
         (timeouts (mapcar (lambda (c) (cons (symbol-name (car c)) (cdr c))) order)))
    ;; slot i belongs to the section i mod n of the anchors
    (dotimes (i count) (push (nth (mod i (length anchors)) anchors) slots))
    (setf slots (if only (copy-list only) (nreverse slots)))
    (flet ((launch (anchor index)
             (let* ((queue (assoc anchor queues :test #'string=))
                    (m (pop (cdr queue))))
               (when m
                 (setf (mutant-index m) index)
                 (let ((claims (by-promise (within-reach-of-time
                                            (claims-for (mutant-unit m) units order reach probed)
                                            (mutant-unit m))
                                           record (unit-anchor (mutant-unit m)))))
                   (setf (mutant-claims m) (length claims))
                 (let ((path (format nil "~A/m~D" directory (incf serial))))
                   (finish-output *standard-output*) (finish-output *error-output*)
                   (let ((pid (sb-posix:fork)))
                     (when (zerop pid)
                       (child m units claims path))
                     (push (make-job :mutant m :pid pid :path path :started (now)) running))))))))
      (let ((index 0))
       (unwind-protect
        (loop while (or slots running)
              do (loop while (and slots (< (length running) jobs))
                       do (let ((anchor (pop slots)))
                            (unless (launch anchor (incf index))
                              ;; the slot goes to the next section that still has mutants
                              (let* ((after (member anchor anchors :test #'string=))
                                     (other (find-if (lambda (a) (cdr (assoc a queues :test #'string=)))
                                                     (append (rest after) (ldiff anchors after)))))
                                (format t "~&(section ~A has no more mutants~@[; its slot goes to ~A~])~%" anchor other)
                                (when other (push other slots))))))
                 (dolist (job running)
                   (let ((m (poll-job job timeouts)))
                     (when m
                       (setf running (remove job running))
                       (ignore-errors (delete-file (job-path job)))
                       (note-claims record job m)
                       (if (eq (mutant-status m) :uncompilable)
                           (progn
                             (format t "~&   (replaced: ~A ~A: ~A)~%" (unit-anchor (mutant-unit m)) (mutant-operator m)
                                     (one-line (mutant-reason m) 80))
                             (push (unit-anchor (mutant-unit m)) slots))
                           (progn (push m finished) (funcall report m (length finished)))))))
                 (sleep 0.05))
         ;; if this image is stopped, its children go with it
         (dolist (job (and (= parent (sb-posix:getpid)) running))
           (ignore-errors (sb-posix:kill (job-pid job) sb-posix:sigkill))
           (ignore-errors (sb-posix:waitpid (job-pid job) 0))))))
      (sort finished #'< :key #'mutant-index)))

;;; ------------------------------------------------------------------------------------
;;; Reports

(defun killed-p (m) (member (mutant-status m) '(:killed :timeout :crashed)))

(defun print-mutant (m n count)
  (let ((u (mutant-unit m)))
    (format t "~&[~3D/~D] ~A ~A (~A:~D) ~A: ~A => ~A~%        ~A~A (~,1F s: ~,1F s compiling, ~D of ~D claims)~%"
            n count (unit-anchor u) (unit-key-name u) (unit-file u) (unit-line u)
            (mutant-operator m) (show u (mutant-from m)) (show u (mutant-to m))
            (case (mutant-status m)
              (:killed (format nil "killed by ~(~A~): " (mutant-claim m)))
              (:timeout (format nil "killed by timeout~@[ in ~(~A~)~]: " (mutant-claim m)))
              (:crashed (format nil "killed by a crash~@[ in ~(~A~)~]: " (mutant-claim m)))
              (t (format nil "SURVIVED the ~D claims that reach it" (mutant-claims m))))
            (if (killed-p m) (one-line (mutant-reason m) 70) "")
            (mutant-seconds m) (mutant-compile-seconds m) (mutant-claims-run m) (mutant-claims m))
    (finish-output)))

(defun page-reasons (page &optional (prefix "Equivalent mutant ~"))
  "Alist from mutant key to the sentence the records file PAGE (*mutant-records*) gives for it:
paragraphs starting 'Equivalent mutant ~KEY~:', or with PREFIX 'Surviving mutant ~' those that
say why a mutant that is not equivalent survives."
  (let ((text (physics::read-file-text page)) (reasons '()) (start 0))
    (loop for at = (search prefix text :start2 start)
          while at
          do (let* ((key-start (+ at (length prefix)))
                    (key-end (search "~:" text :start2 key-start))
                    ;; a record ends at a blank line, or where its drawer closes
                    (end (min (or (search (format nil "~%~%") text :start2 key-start) (length text))
                              (or (search (format nil "~%:END:") text :start2 key-start) (length text)))))
               (when (and key-end (< key-end end))
                 (push (cons (subseq text key-start key-end)
                             (one-line (string-trim '(#\Space #\Newline) (subseq text (+ key-end 2) end)) 400))
                       reasons))
               (setf start (1+ at))))
    reasons))

(defun page-reason (key reasons)
  "The page's sentence for the mutant named KEY: the one given for KEY itself, or for a name
ending in ': *', which stands for every mutant of that definition."
  (cdr (or (assoc key reasons :test #'string=)
           (find-if (lambda (entry)
                      (let ((name (car entry)))
                        (and (>= (length name) 3) (string= ": *" name :start2 (- (length name) 3))
                             (physics::starts-with (subseq name 0 (- (length name) 1)) key))))
                    reasons))))

(defun score-table (mutants parts stream)
  (let ((reasons (page-reasons *mutant-records*)))
    (write-score-rows (loop for m in mutants
                            collect (list (gethash (unit-anchor (mutant-unit m)) parts "?")
                                          (unit-anchor (mutant-unit m))
                                          (and (page-reason (mutant-key m) reasons) t)
                                          (mutant-operator m)
                                          (killed-p m)))
                      stream)))

(defun write-score-rows (scored stream)
  "SCORED holds one list per mutant: its part, its anchor, whether the page explains it as
equivalent, its operator, and last whether it was killed.  The score of the rest leaves out the
survivors the page explains as equivalent.  A table by part, then the same mutants by operator."
  (write-score-rows-by #'first "part" scored stream)
  (terpri stream)
  (write-score-rows-by #'fourth "operator" scored stream))

(defun write-score-rows-by (key heading scored stream)
  (let ((rows '()))
    (dolist (x scored)
      (let* ((part (funcall key x)) (killed (car (last x))) (equivalent (and (not killed) (third x)))
             (row (or (assoc part rows :test #'string=) (car (push (list part 0 0 '() 0) rows)))))
        (incf (second row))
        (when killed (incf (third row)))
        (when equivalent (incf (fifth row)))
        (pushnew (second x) (fourth row) :test #'string=)))
    (setf rows (sort rows #'string< :key #'first))
    (flet ((line (name sections n k e)
             (format stream "| ~A | ~D | ~D | ~D | ~D | ~D | ~,1F % | ~,1F % |~%" name sections n k (- n k e) e
                     (* 100 (/ k (max 1 n))) (* 100 (/ k (max 1 (- n e)))))))
      (format stream "| ~A | sections | mutants | killed | survived | equivalent | score | score without equivalents |~%|-~%" heading)
      (dolist (r rows)
        (line (first r) (length (fourth r)) (second r) (third r) (fifth r)))
      (format stream "|-~%")
      (line "all" (length (remove-duplicates (mapcar #'second scored) :test #'string=))
            (length scored) (count-if (lambda (x) (car (last x))) scored)
            (count-if (lambda (x) (and (not (car (last x))) (third x))) scored)))))

(defun survivor-rows (mutants)
  "One list (ANCHOR OPERATOR FILE KEY) per surviving mutant of MUTANTS."
  (loop for m in (remove-if #'killed-p mutants)
        collect (list (unit-anchor (mutant-unit m)) (mutant-operator m) (unit-file (mutant-unit m))
                      (mutant-key m))))

(defun survivors-list (rows reasons stream)
  "Write the survivors ROWS, each with the page's reason from REASONS, to STREAM."
  (if (null rows)
      (format stream "No mutant survived.~%")
      (loop for (anchor operator file key) in rows
            do (format stream "- ~A ~A, ~A: ~A~%    ~A~%" anchor operator file key
                       (or (page-reason key reasons)
                           (let ((why (page-reason key (page-reasons *mutant-records* "Surviving mutant ~"))))
                             (and why (format nil "not equivalent: ~A" why)))
                           "(no reason given in the records)")))))

(defun annotate-survivors ()
  "Write report/mutate-survivors.org from report/mutate-survivors.tsv and the page's reasons,
as they are now."
  (let ((rows (with-open-file (in "report/mutate-survivors.tsv")
                (loop for line = (read-line in nil) while line
                      collect (uiop:split-string line :separator '(#\Tab))))))
    (with-open-file (out "report/mutate-survivors.org" :direction :output :if-exists :supersede)
      (survivors-list rows (page-reasons *mutant-records*) out))))

;;; ------------------------------------------------------------------------------------
;;; Tables from a log: the lines a run printed, for a run stopped before its end

(defparameter *operators* '("comparison flip" "sign flip" "constant scaling" "off-by-one"
                            "dropped form" "swapped arguments" "wrong variable" "wrong column"
                            "dropped check"))

(defun tables-from-log (log parts)
  "Read the mutant lines of the run logged in LOG and write the score table and the survivors
as a finished run does.  Return the number of mutants read."
  (let ((lines (with-open-file (in log) (loop for line = (read-line in nil) while line collect line)))
        (rows '())
        ;; a log written before its names were whole cut a long name short with "...": such a
        ;; name is the unit's whose whole name begins so
        (names (mapcar #'unit-key-name (loop for file in *dependent-files* append (read-units file)))))
    (loop for (line next) on lines
          when (and (physics::starts-with "[" line) (search "] " line) next)
            do (let* ((head (+ 2 (search "] " line)))
                      (anchor (subseq line head (position #\Space line :start head)))
                      (name-start (+ head (length anchor) 1))
                      (file-start (search " (tangled/" line :start2 name-start))
                      (file-end (and file-start (position #\: line :start file-start)))
                      (after (and file-end (+ 2 (position #\) line :start file-end))))
                      (operator (and after (find-if (lambda (op) (eql after (search (concatenate 'string op ": ") line :start2 after)))
                                                    *operators*))))
                 (when operator
                   (push (list anchor operator (subseq line (+ 2 file-start) file-end)
                               (format nil "~A: ~A"
                                       (let ((name (subseq line name-start file-start)))
                                         (if (and (> (length name) 3) (string= "..." name :start2 (- (length name) 3)))
                                             (or (find-if (lambda (whole) (physics::starts-with (subseq name 0 (- (length name) 3)) whole))
                                                          names)
                                                 name)
                                             name))
                                       (subseq line (+ after (length operator) 2)))
                               (not (search "SURVIVED" next)))
                         rows))))
    (setf rows (nreverse rows))
    (let ((summary (find-if (lambda (l) (and (physics::starts-with "mutate: " l) (search "mutants killed" l))) lines))
          (first-line (find-if (lambda (l) (physics::starts-with "mutate: seed" l)) lines))
          (reasons (page-reasons *mutant-records*)))
      (with-open-file (out "report/mutate-score.org" :direction :output :if-exists :supersede)
        (format out "~A~%~A~%~%" (or first-line "") (or summary (format nil "~D mutants read from ~A, a run stopped before its end" (length rows) log)))
        (write-score-rows (mapcar (lambda (r) (list (gethash (first r) parts "?") (first r)
                                                    (and (page-reason (fourth r) reasons) t)
                                                    (second r)
                                                    (fifth r)))
                                  rows)
                          out)))
    (with-open-file (out "report/mutate-survivors.tsv" :direction :output :if-exists :supersede)
      (loop for r in rows unless (fifth r) do (format out "~{~A~^	~}~%" (subseq r 0 4))))
    (annotate-survivors)
    (length rows)))

;;; ------------------------------------------------------------------------------------
;;; Main

(defun main ()
  (let* ((seed (getenv-integer "SEED" 1))
         (count (getenv-integer "COUNT" 150))
         (jobs (getenv-integer "JOBS" 2))
         (anchor (let ((a (string-upcase (string-trim " #" (or (sb-ext:posix-getenv "ANCHOR") "")))))
                   (and (plusp (length a)) a)))
         (start (now))
         (units (loop for file in *dependent-files* append (read-units file)))
         (inline (note-inline-names units))
         (parts (setf *parts* (anchor-parts "physics.org")))
         (slow (setf *slow* (let ((v (sb-ext:posix-getenv "SLOW")))
                              (if (and v (plusp (length v))) (float (read-from-string v) 1d0) *slow*))))
         (layouts (setf *layouts* (unit-layouts units)))
         (sections (drawn-sections (section-sites units anchor (let ((m (sb-ext:posix-getenv "MATCH"))) (and (plusp (length m)) m)))
                                   seed))
         (only-parts (let ((p (sb-ext:posix-getenv "PART")))
                       (and p (plusp (length p)) (uiop:split-string p :separator "|"))))
         (only '()))
    (declare (ignore inline layouts))
    (when (null sections)
      (format t "~&mutate: no definitions to mutate~@[ in section ~A~]~%" anchor)
      (sb-ext:exit :code 1))
    (when (plusp (length (sb-ext:posix-getenv "LIST")))
      (list-draw sections count parts)
      (sb-ext:exit :code 0))
    (when only-parts
      (setf only (loop for (anchor) in (draw sections count)
                       when (member (gethash anchor parts) only-parts :test #'string=) collect anchor))
      (format t "~&mutate: of the ~D mutants drawn, only the ~D of ~{~A~^, ~} run~%" count (length only) only-parts))
    (dolist (c luv-physics-tests:*claims*) (setf (gethash (cdr c) *claim-anchors*) (car c)))
    (setf *precompiled-variants* (loop for key being the hash-keys of physics::*featured-kernels* collect key))
    (read-record)
    (format t "~&mutate: seed ~D, ~D mutants over ~D sections (~D sites), ~D at a time, claims over ~,0F % of the claims' time only in their own part; load ~A~%"
            seed count (length sections) (reduce #'+ sections :key (lambda (s) (length (cdr s)))) jobs (* 100 slow)
            (load-average))
    (multiple-value-bind (order failing reach)
        (let* ((path (format nil "/tmp/luv-mutate-reach-~D.sexp" (sb-posix:getpid)))
               (pid (claims-reach-in-child luv-physics-tests:*claims* (probed-names units) path)))
          (multiple-value-bind (order failing) (time-claims luv-physics-tests:*claims*)
            (values order failing (read-reach pid path order))))
      (format t "~&mutate: ~D claims pass on the unchanged engine in ~,1F s~@[; left out, failing: ~{~(~A~)~^ ~}~]~%"
              (length order) (reduce #'+ order :key #'cdr) failing)
      (setf *claims-seconds* (reduce #'+ order :key #'cdr))
      (format t "~&mutate: the slowest: ~{~{~(~A~) ~,1F s~}~^, ~}~%"
              (mapcar (lambda (c) (list (car c) (cdr c))) (reverse (last order 12))))
      (finish-output)
      (let* ((probed (probed-names units))
             (reach (or reach (claims-reach order probed)))
             (dummy (format t "~&mutate: ~D functions watched by probes; each claim reaches ~D of them on average~%"
                            (length probed) (round (reduce #'+ reach :key (lambda (r) (length (cdr r)))) (max 1 (length reach)))))
             (directory (format nil "/tmp/luv-mutate-~D" (sb-posix:getpid)))
             (mutants (progn (ensure-directories-exist (format nil "~A/" directory))
                             (run-mutants sections count units order reach probed jobs directory
                                          (lambda (m n) (print-mutant m n (if only (length only) count)))
                                          only)))
             (saved (progn (ensure-directories-exist "report/") (write-record)))
             (wall (- (now) start))
             (reasons (page-reasons *mutant-records*)))
        (declare (ignore dummy saved))
        (ignore-errors (sb-ext:delete-directory directory :recursive t))
        (let ((n (length mutants)) (k (count-if #'killed-p mutants)))
          (format t "~&~%mutate: ~D of ~D mutants killed (~,1F %), ~D survived; ~,1F s in all, ~,1F s a mutant on average in its child; load ~A~%~%"
                  k n (* 100 (/ k (max 1 n))) (- n k) wall
                  (/ (reduce #'+ mutants :key #'mutant-seconds) (max 1 n))
                  (load-average)))
        (ensure-directories-exist "report/")
        (with-open-file (out "report/mutate-score.org" :direction :output :if-exists :supersede)
          (format out "seed ~D, ~D mutants, ~,1F s a mutant on average (two at a time), ~D s in all~%~%"
                  seed (length mutants) (/ (reduce #'+ mutants :key #'mutant-seconds) (max 1 (length mutants))) (round wall))
          (score-table mutants parts out))
        (with-open-file (out "report/mutate-survivors.tsv" :direction :output :if-exists :supersede)
          (loop for row in (survivor-rows mutants) do (format out "~{~A~^	~}~%" row)))
        (annotate-survivors)
        (score-table mutants parts *standard-output*)
        (terpri)
        (survivors-list (survivor-rows mutants) reasons *standard-output*)))))

(cond ((sb-ext:posix-getenv "MUTATE_NO_MAIN"))
      ((sb-ext:posix-getenv "MUTATE_ANNOTATE") (annotate-survivors))
      ((sb-ext:posix-getenv "MUTATE_FROM_LOG")
       (format t "~&mutate: ~D mutants read from ~A~%"
               (tables-from-log (sb-ext:posix-getenv "MUTATE_FROM_LOG") (anchor-parts "physics.org"))
               (sb-ext:posix-getenv "MUTATE_FROM_LOG")))
      (t (main)))
